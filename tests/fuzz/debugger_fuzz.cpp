// libFuzzer target of the step debugger's command lines: each line of the input is one
// command typed outside a run, against a small program compiled from two "files"; `run`
// only reports that the program would start, so nothing executes.
#include <optional>
#include <sstream>

#include "frontend/frontend.h"
#include "fuzz_support.h"
#include "repl/debugger.h"

namespace {

using namespace simit;

// a.sim (compiled lines 1-4) then b.sim (compiled lines 5-13).
const char* const kProgram =
    "func sq(x : float) -> y : float\n"
    "  y = x * x;\n"
    "end\n"
    "\n"
    "% b.sim\n"
    "element Point\n  u : float;\nend\n"
    "extern points : set{Point};\n"
    "export func main(a : float) -> r : float\n"
    "  var s = sq(a);\n"
    "  for i in 0:2\n"
    "    s = s + 1.0;\n"
    "  end\n"
    "  r = s;\n"
    "end\n";

// Enough commands to reach every state outside a run; more only repeat them.
constexpr int kMaxLines = 64;

const frontend::ast::Program& program() {
  static std::unique_ptr<frontend::Compilation> c = [] {
    auto compiled = frontend::compile_source("<repl>", kProgram);
    if (!compiled->ok())
      fuzz::invariant_broken("debugger_fuzz", compiled->diagnostics.render_all());
    return compiled;
  }();
  return *c->program;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::ostringstream out, err;
  repl::Debugger debugger(
      out, err, [](const std::string&) -> std::optional<std::string> { return std::nullopt; });
  debugger.set_program(&program(), {{1, "a.sim", 1}, {5, "b.sim", 1}});
  std::vector<std::string_view> lines =
      fuzz::split_parts(fuzz::as_text(data, size), '\n', kMaxLines);
  for (std::string_view line : lines) {
    std::string run_args;
    std::string text(line.substr(0, line.find('\n')));
    (void)repl::Debugger::is_command(text.substr(0, text.find(' ')));
    if (debugger.command(text, run_args) == repl::Debugger::Outcome::Quit) break;
  }
  if (!err.str().empty()) fuzz::note_rejected("debugger_fuzz", err.str());
  return 0;
}
