// The frontend pipeline driver: one flat list of passes.
#include "frontend/frontend.h"

#include <fstream>
#include <sstream>

#include "frontend/assembly_writes.h"
#include "frontend/checker.h"
#include "frontend/extern_uses.h"
#include "frontend/hoisting.h"
#include "frontend/index_ranges.h"
#include "frontend/lexer.h"
#include "frontend/parser.h"
#include "frontend/system_statements.h"

namespace simit::frontend {

std::unique_ptr<Compilation> compile_source(std::string name, std::string text,
                                            const CompileOptions& options) {
  auto c = std::make_unique<Compilation>();
  c->source = std::make_unique<SourceFile>(std::move(name), std::move(text));
  std::vector<Token> tokens = lex(*c->source, c->diagnostics);
  c->program = parse(tokens, c->diagnostics);
  // A tree with syntax errors is incomplete; checking it would only add noise.
  if (options.check && !c->diagnostics.has_errors()) check(*c->program, c->diagnostics);
  // Analyses, once per program, for every executor.
  if (c->ok() && options.check) {
    plan_hoisting(*c->program);
    mark_system_statements(*c->program);
    mark_assembly_writes(*c->program);
    plan_index_ranges(*c->program);
    plan_extern_uses(*c->program);
  }
  return c;
}

std::unique_ptr<Compilation> compile_file(const std::string& path, const CompileOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    auto c = std::make_unique<Compilation>();
    c->source = std::make_unique<SourceFile>(path, "");
    c->diagnostics.syntax({}, "cannot read file '" + path + "'");
    return c;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return compile_source(path, ss.str(), options);
}

}  // namespace simit::frontend
