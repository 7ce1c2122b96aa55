// The step debugger driven in-process: a program compiled from two concatenated "files" (as
// the REPL compiles its loaded files), breakpoints and stops in real file names and lines,
// the hook installed only while something needs it, and quitting from a stop.
#include "repl/debugger.h"

#include <gtest/gtest.h>

#include <chrono>
#include <deque>
#include <sstream>
#include <thread>

#include "frontend/frontend.h"
#include "interp/interpreter.h"
#include "repl/line_map.h"

namespace simit::repl {
namespace {

// a.sim (compiled lines 1-4) then b.sim (compiled lines 5-12).
const char* const kFileA =
    "func sq(x : float) -> y : float\n"  // a.sim:1
    "  y = x * x;\n"                     // a.sim:2
    "end\n"                              // a.sim:3
    "\n";                                // a.sim:4
const char* const kFileB =
    "% b.sim\n"                                   // b.sim:1
    "export func main(a : float) -> r : float\n"  // b.sim:2
    "  var s = sq(a);\n"                          // b.sim:3
    "  for i in 0:2\n"                            // b.sim:4
    "    s = s + 1.0;\n"                          // b.sim:5
    "  end\n"                                     // b.sim:6
    "  r = s;\n"                                  // b.sim:7
    "end\n";                                      // b.sim:8

class DebugRun {
 public:
  explicit DebugRun(std::vector<std::string> script, const char* file_b = kFileB)
      : script_(script.begin(), script.end()),
        c_(frontend::compile_source("<repl>", std::string(kFileA) + file_b)),
        debugger_(out_, out_, [this](const std::string&) -> std::optional<std::string> {
          if (script_.empty()) return std::nullopt;
          std::string line = script_.front();
          script_.pop_front();
          out_ << "> " << line << "\n";
          return line;
        }) {
    EXPECT_TRUE(c_->ok()) << c_->diagnostics.render_all();
    debugger_.set_program(c_->program.get(), {{1, "a.sim", 1}, {5, "b.sim", 1}});
  }
  // Runs commands until `run`, then main(3.0); returns the result (NaN when it threw).
  double run_until_done() {
    std::string args;
    while (!script_.empty()) {
      std::string line = script_.front();
      script_.pop_front();
      out_ << "> " << line << "\n";
      Debugger::Outcome o = debugger_.command(line, args);
      if (o == Debugger::Outcome::Quit) return NAN;
      if (o == Debugger::Outcome::Run) return call();
    }
    return NAN;
  }
  double call() {
    interp::Options o;
    o.trap = &debugger_.trap();
    interp::Interpreter in(*c_->program, o);
    debugger_.begin_run();
    armed_at_start_ = debugger_.trap().armed();
    double r = NAN;
    try {
      r = in.call(*c_->program->find_func("main"), {interp::Value::of_float(3.0)})[0].as_float();
    } catch (const interp::RuntimeError& e) {
      out_ << "[" << e.message() << "]\n";
    }
    killed_ = debugger_.end_run();
    return r;
  }
  std::string output() const { return out_.str(); }
  bool armed_at_start() const { return armed_at_start_; }
  bool killed() const { return killed_; }
  Debugger& debugger() { return debugger_; }

 private:
  std::deque<std::string> script_;
  std::ostringstream out_;
  std::unique_ptr<frontend::Compilation> c_;
  Debugger debugger_;
  bool armed_at_start_ = false, killed_ = false;
};

TEST(LineMap, MapsConcatenatedFiles) {
  LineMap m({{5, "lib/b.sim", 1}, {1, "a.sim", 1}});
  EXPECT_EQ(m.place(2).file, "a.sim");
  EXPECT_EQ(m.place(7).file, "lib/b.sim");
  EXPECT_EQ(m.place(7).line, 3);
  EXPECT_EQ(m.compiled_line("b.sim", 3), 7);  // by base name
  EXPECT_EQ(m.compiled_line("lib/b.sim", 3), 7);
  EXPECT_EQ(m.compiled_line("a.sim", 4), 4);
  EXPECT_EQ(m.compiled_line("a.sim", 5), std::nullopt);  // b.sim's lines are not a.sim's
  EXPECT_EQ(m.compiled_line("c.sim", 1), std::nullopt);
  EXPECT_EQ(m.default_file(), "a.sim");
}

TEST(Debugger, BreaksAndReportsInTheRealFilesOfAConcatenatedSource) {
  DebugRun s({"break b.sim:3", "break sq", "run", "backtrace", "print x", "continue", "print s",
              "next", "print s + 0.5", "info locals", "continue"});
  double r = s.run_until_done();
  EXPECT_EQ(r, 11.0);
  EXPECT_TRUE(s.armed_at_start());
  EXPECT_FALSE(s.killed());
  const std::string want =
      "> break b.sim:3\n"
      "Breakpoint 1 at main, b.sim:3\n"
      "> break sq\n"
      "Breakpoint 2 at sq, a.sim:2\n"
      "> run\n"
      "Breakpoint 1, main at b.sim:3\n"
      "3\t  var s = sq(a);\n"
      "> backtrace\n"
      "#0  main at b.sim:3\n"
      "> print x\n"
      "undeclared variable or constant 'x'\n"
      "> continue\n"
      "Breakpoint 2, sq at a.sim:2\n"
      "2\t  y = x * x;\n"
      "> print s\n"
      "undeclared variable or constant 's'\n"
      "> next\n"
      "main just after b.sim:3\n"
      "3\t  var s = sq(a);\n"
      "> print s + 0.5\n"
      "s + 0.5 = 9.5\n"
      "> info locals\n"
      "a = 3.0\n"
      "r = 0.0\n"
      "s = 9.0\n"
      "> continue\n";
  EXPECT_EQ(s.output(), want);
}

// The debugger stops on an error statement like any other; continuing raises the error.
TEST(Debugger, StepsOntoAnErrorStatement) {
  const char* const file_b =
      "% b.sim\n"                                   // b.sim:1
      "export func main(a : float) -> r : float\n"  // b.sim:2
      "  r = sq(a);\n"                              // b.sim:3
      "  if r > 4.0\n"                              // b.sim:4
      "    error \"r = \", r, \" > 4\";\n"          // b.sim:5
      "  end\n"                                     // b.sim:6
      "end\n";                                      // b.sim:7
  DebugRun s({"break b.sim:4", "run", "step", "print r", "continue"}, file_b);
  EXPECT_TRUE(std::isnan(s.run_until_done()));
  EXPECT_FALSE(s.killed());
  const std::string want =
      "> break b.sim:4\n"
      "Breakpoint 1 at main, b.sim:4\n"
      "> run\n"
      "Breakpoint 1, main at b.sim:4\n"
      "4\t  if r > 4.0\n"
      "> step\n"
      "5\t    error \"r = \", r, \" > 4\";\n"
      "> print r\n"
      "r = 9.0\n"
      "> continue\n"
      "[r = 9 > 4]\n";
  EXPECT_EQ(s.output(), want);
}

TEST(Debugger, NoHookWithoutBreakpointsAndQuitEndsTheRun) {
  DebugRun plain({"run"});
  EXPECT_EQ(plain.run_until_done(), 11.0);
  EXPECT_FALSE(plain.armed_at_start());  // nothing to stop at: the trap point stays off

  DebugRun quitting({"tbreak sq", "run", "info breakpoints", "quit"});
  EXPECT_TRUE(std::isnan(quitting.run_until_done()));
  EXPECT_TRUE(quitting.killed());
  EXPECT_TRUE(quitting.debugger().quit_requested());
  EXPECT_NE(quitting.output().find("Temporary breakpoint 1, sq at a.sim:2\n"), std::string::npos)
      << quitting.output();
  EXPECT_NE(quitting.output().find("> info breakpoints\nNo breakpoints or watchpoints.\n"),
            std::string::npos);
  EXPECT_NE(quitting.output().find("[the debugger ended the run]"), std::string::npos);
}

TEST(Debugger, KnowsItsCommands) {
  EXPECT_TRUE(Debugger::is_command("break"));
  EXPECT_TRUE(Debugger::is_command("b"));
  EXPECT_TRUE(Debugger::is_command("bt"));
  EXPECT_TRUE(Debugger::is_command("wat"));
  EXPECT_FALSE(Debugger::is_command("load"));
  EXPECT_FALSE(
      Debugger::is_command("d"
                           "x"));
}

// The arguments of break and watch are scanned by hand: a condition of 30,000 characters
// gets the frontend's own error (std::regex recursed once per character and overflowed the
// stack), and the forms the commands accept are unchanged.
TEST(Debugger, BreakAndWatchArgumentsOfAnyLength) {
  std::string deep = std::string(15000, '(') + "x > 1.0" + std::string(15000, ')');
  DebugRun s({"break sq if " + deep, "break sq   if   x > 1.0", "break if x > 1.0", "break sq if",
              "watch verts.x[3]", "watch verts.x ( 3 )", "watch verts.x[3", "watch verts.[3]",
              "watch verts.x[99999999999]", "break 99999999999", "info breakpoints"});
  s.run_until_done();
  std::string got = s.output();
  got.replace(got.find(deep), deep.size(), "DEEP");
  const std::string want =
      "> break sq if DEEP\n"
      "Cannot set the breakpoint: in the condition: nested too deeply: more than 256 levels of "
      "blocks, parentheses, calls or prefix operators.\n"
      "> break sq   if   x > 1.0\n"
      "Breakpoint 1 at sq, a.sim:2\n"
      "> break if x > 1.0\n"
      "break needs a location: LINE, FILE:LINE or FUNC.\n"
      "> break sq if\n"
      "Cannot set the breakpoint: no function 'sq if' in the program.\n"
      "> watch verts.x[3]\n"
      "Cannot watch verts.x[3]: no set named 'verts' in the program.\n"
      "> watch verts.x ( 3 )\n"
      "Cannot watch verts.x ( 3 ): no set named 'verts' in the program.\n"
      "> watch verts.x[3\n"
      "watch needs SET.FIELD[i], e.g. watch verts.x[3]\n"
      "> watch verts.[3]\n"
      "watch needs SET.FIELD[i], e.g. watch verts.x[3]\n"
      "> watch verts.x[99999999999]\n"
      "watch: there is no element 99999999999 (the index is too large)\n"
      "> break 99999999999\n"
      "no line 99999999999 in a file named 'a.sim' in the program\n"
      "> info breakpoints\n"
      "Num  Type        What\n"
      "1    breakpoint  sq at a.sim:2\n"
      "        stop only if x > 1.0\n";
  EXPECT_EQ(got, want);
}

// Breakpoints outlive the program of a run (the REPL compiles one per input and frees it
// after the run): `info breakpoints` afterwards reads nothing of it. Under AddressSanitizer
// this read freed memory while breakpoints kept their pointers after the run.
TEST(Debugger, InfoAfterTheRunsProgramIsFreed) {
  const std::string text = std::string(kFileA) + kFileB;
  const std::vector<LineSegment> files = {{1, "a.sim", 1}, {5, "b.sim", 1}};
  auto kept = frontend::compile_source("<repl>", text);
  ASSERT_TRUE(kept->ok()) << kept->diagnostics.render_all();
  std::ostringstream out;
  Debugger d(out, out, [](const std::string&) { return std::optional<std::string>("continue"); });
  d.set_program(kept->program.get(), files);
  std::string args;
  d.command("break sq if x > 100.0", args);
  d.command("tbreak b.sim:5", args);
  {
    auto run = frontend::compile_source("<repl>", text);
    ASSERT_TRUE(run->ok());
    d.set_program(run->program.get(), files);
    interp::Options o;
    o.trap = &d.trap();
    auto in = std::make_unique<interp::Interpreter>(*run->program, o);
    d.begin_run();
    // The run stops at b.sim:5 (the tbreak, deleted then) and continues.
    in->call(*run->program->find_func("main"), {interp::Value::of_float(3.0)});
    d.end_run();
    in.reset();
    run.reset();  // the run's program is gone, as after a REPL input
  }
  d.set_program(kept->program.get(), files);
  out.str("");
  d.command("info breakpoints", args);
  EXPECT_EQ(out.str(),
            "Num  Type        What\n"
            "1    breakpoint  sq at a.sim:2\n"
            "        stop only if x > 100.0\n");
}

// Ctrl-C in `simit debug` (request_pause, from another thread here) stops an endless loop
// at its next statement with no breakpoint set; the debugger then reads commands there.
TEST(Debugger, PauseStopsARunWithoutBreakpoints) {
  if (!interp::kStatementHook)
    GTEST_SKIP() << "built with SIMIT_STATEMENT_HOOK=OFF: no trap point to pause at";
  auto c = frontend::compile_source(
      "loop.sim", "export func main() -> (n : int)\n  while true\n    n = n + 1;\n  end\nend\n");
  ASSERT_TRUE(c->ok()) << c->diagnostics.render_all();
  std::ostringstream out;
  std::deque<std::string> script = {"print n > 0", "kill"};
  Debugger d(out, out, [&](const std::string&) -> std::optional<std::string> {
    if (script.empty()) return std::nullopt;
    std::string line = script.front();
    script.pop_front();
    return line;
  });
  d.set_program(c->program.get());
  interp::Options o;
  o.trap = &d.trap();
  interp::Interpreter in(*c->program, o);
  d.begin_run();
  EXPECT_FALSE(d.trap().armed());  // nothing set: the loop runs with the hook off
  std::thread pauser([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    d.request_pause();
  });
  EXPECT_THROW(in.call(*c->program->find_func("main"), {}), interp::RuntimeError);
  pauser.join();
  EXPECT_TRUE(d.end_run());  // ended by `kill`
  EXPECT_NE(out.str().find("Interrupted (Ctrl-C)."), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("n > 0 = true"), std::string::npos) << out.str();
}

}  // namespace
}  // namespace simit::repl
