// libFuzzer target over the whole frontend: lex, parse, check, render, dump and re-print.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "frontend/frontend.h"
#include "frontend/printer.h"

namespace {

using simit::frontend::Compilation;
using simit::frontend::CompileOptions;
using simit::frontend::DiagCategory;

[[noreturn]] void invariant_broken(const char* what, const std::string& text) {
  std::fprintf(stderr, "frontend_fuzz: %s\n--- printed source ---\n%s\n", what, text.c_str());
  std::abort();
}

bool parsed_cleanly(const Compilation& c) {
  if (!c.program) return false;
  for (const auto& d : c.diagnostics.items())
    if (d.category != DiagCategory::Semantic) return false;
  return true;
}

// A tree the parser accepted prints to source that parses again, to the same text.
void check_round_trip(const Compilation& c) {
  std::string printed = simit::frontend::print_source(*c.program);
  CompileOptions parse_only;
  parse_only.check = false;
  auto again = simit::frontend::compile_source("printed.sim", printed, parse_only);
  if (!parsed_cleanly(*again)) invariant_broken("printed source does not parse", printed);
  if (simit::frontend::print_source(*again->program) != printed)
    invariant_broken("printing is not stable under re-parsing", printed);
}

}  // namespace

// Internal errors (SIMIT_ASSERT) are not caught: for the fuzzer they are crashes.
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  auto c = simit::frontend::compile_source("fuzz.sim", std::move(text));
  std::string rendered = c->diagnostics.render_all();
  if (!c->ok() && rendered.empty()) invariant_broken("rejected without a diagnostic", "");
  if (parsed_cleanly(*c)) {
    check_round_trip(*c);
    (void)simit::frontend::dump_ast(*c->program);
  }
  if (c->ok()) (void)simit::frontend::dump_typed(*c->program);
  return 0;
}
