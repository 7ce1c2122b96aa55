// `simit check`: parse and type-check programs, print diagnostics and optional tree dumps.
#include "simit/commands.h"

#include <algorithm>
#include <exception>
#include <memory>
#include <vector>

#include "frontend/frontend.h"
#include "frontend/printer.h"
#include "testing/files.h"

namespace simit::tools {
namespace {

using frontend::Compilation;
using frontend::DiagCategory;

bool wants(const CheckOptions& options, const char* dump) {
  return std::find(options.dumps.begin(), options.dumps.end(), dump) != options.dumps.end();
}

// A tree with lexical or syntax errors is incomplete and is not dumped.
bool parsed_cleanly(const Compilation& c) {
  if (!c.program) return false;
  return std::none_of(c.diagnostics.items().begin(), c.diagnostics.items().end(),
                      [](const auto& d) { return d.category != DiagCategory::Semantic; });
}

void print_dumps(const Compilation& c, const CheckOptions& options, std::ostream& out) {
  // Headers only when several trees are printed, so a single dump pipes cleanly.
  bool headers = options.files.size() > 1 || options.dumps.size() > 1;
  if (wants(options, "ast") && parsed_cleanly(c)) {
    if (headers) out << "# ast of " << c.source->name() << "\n";
    out << frontend::dump_ast(*c.program);
  }
  if (wants(options, "typed") && c.ok()) {
    if (headers) out << "# typed of " << c.source->name() << "\n";
    out << frontend::dump_typed(*c.program);
  }
}

// `simit check` exits right after checking: tearing the trees down node by node would cost
// more than a tenth of its time for nothing (compilers skip it too, e.g. clang's
// -disable-free). The holder is never destroyed, so the trees stay reachable, not leaked.
void keep_until_exit(std::unique_ptr<Compilation> c) {
  static auto* kept = new std::vector<std::unique_ptr<Compilation>>();
  kept->push_back(std::move(c));
}

bool check_one(const std::string& path, const CheckOptions& options, std::ostream& out,
               std::ostream& err) {
  std::string error;
  std::optional<std::string> text = read_text_file(path, error);
  if (!text) {
    err << "simit check: cannot read '" << path << "': " << error << "\n";
    return false;
  }
  std::unique_ptr<Compilation> c = frontend::compile_source(path, std::move(*text));
  err << c->diagnostics.render_all();
  print_dumps(*c, options, out);
  bool ok = c->ok();
  keep_until_exit(std::move(c));
  return ok;
}

}  // namespace

int run_check(const CheckOptions& options, std::ostream& out, std::ostream& err) {
  bool clean = true;
  for (const auto& path : options.files) {
    try {
      clean = check_one(path, options, out, err) && clean;
    } catch (const std::exception& e) {
      // Internal failures are not user diagnostics; say so plainly and go on.
      err << path << ": internal compiler error: " << e.what() << "\n";
      clean = false;
    }
  }
  return clean ? 0 : 1;
}

}  // namespace simit::tools
