// Diagnostics met while porting programs from the original Simit: each says what to write
// here, where the plain message would leave a porter guessing.
#include <gtest/gtest.h>

#include "frontend/frontend.h"

namespace simit::frontend {
namespace {

std::unique_ptr<Compilation> compile(const std::string& source) {
  return compile_source("t.sim", source);
}

// "<line>:<column> <category>: <message>" of every diagnostic, in order.
std::vector<std::string> messages(const std::string& source) {
  std::vector<std::string> out;
  auto c = compile(source);
  for (const auto& d : c->diagnostics.items()) {
    LineCol lc = d.span.start();
    out.push_back(std::to_string(lc.line) + ":" + std::to_string(lc.column) + " " +
                  category_name(d) + ": " + d.message);
  }
  return out;
}

using Lines = std::vector<std::string>;

// The original Simit's `proc NAME ... end` is written `export func NAME()` here. The
// procedure is skipped whole: the `const` and `end` inside it give no further errors, and
// the program element after it is parsed.
TEST(PortingMessages, ProcIsWrittenExportFunc) {
  EXPECT_EQ(messages("const c = 1.0;\n"
                     "  proc main\n"
                     "  const k = 2.0;\n"
                     "  if c > 0.0\n"
                     "    print k;\n"
                     "  end\n"
                     "end\n"
                     "func f() -> r : float\n"
                     "  r = 1.0 +;\n"
                     "end\n"),
            (Lines{"2:3 syntax: 'proc' is not a keyword here: an exported procedure is written "
                   "'export func main()'",
                   "9:12 syntax: expected an expression but got ';'"}));
  EXPECT_EQ(messages("proc\nend\n"),
            (Lines{"1:1 syntax: 'proc' is not a keyword here: an exported procedure is written "
                   "'export func NAME()'"}));
}

// A name bound twice keeps the not-writable error and says how to make it assignable,
// where declaring it with `var` would.
TEST(PortingMessages, NotWritableSuggestsVar) {
  EXPECT_EQ(messages("export func main()\n"
                     "  const x = 1.0;\n"
                     "  x = 2.0;\n"
                     "end\n"),
            (Lines{"3:3 not-writable: assignment target is not writable: 'x' is a local 'const'; "
                   "declare it with 'var' to assign it again"}));
  EXPECT_EQ(messages("export func main()\n"
                     "  x = 1.0;\n"
                     "  x = 2.0;\n"
                     "  v = [1.0, 2.0];\n"
                     "  v(0) = 3.0;\n"
                     "end\n"),
            (Lines{"3:3 not-writable: assignment target is not writable: 'x' was declared by its "
                   "first assignment, which makes it read-only; declare it with 'var' to assign "
                   "it again",
                   "5:3 not-writable: assignment target is not writable: 'v' was declared by its "
                   "first assignment, which makes it read-only; declare it with 'var' to assign "
                   "it again"}));
  EXPECT_EQ(messages("func f(a : vector[2](float)) -> r : float\n"
                     "  a(1) = 0.0;\n"
                     "  r = a(0);\n"
                     "end\n"),
            (Lines{"2:3 not-writable: assignment target is not writable: parameter 'a' is "
                   "read-only; to change a copy, declare one with 'var' ('var a = a;')"}));
  // The copy the message suggests is legal.
  EXPECT_TRUE(compile("func f(a : vector[2](float)) -> r : float\n"
                      "  var a = a;\n"
                      "  a(1) = 0.0;\n"
                      "  r = a(1);\n"
                      "end\n")
                  ->ok());
}

// Where `var` would not help, the message stays plain: a global constant (no `var` at
// global scope), a loop variable, an opaque handle, a slice, an index variable.
TEST(PortingMessages, NotWritableWithoutAHint) {
  const std::string plain = "assignment target is not writable";
  const char* const sources[] = {
      "const g = 1.0;\nexport func main()\n  g = 2.0;\nend\n",
      "export func main()\n  for i in 0:3\n    i = 1;\n  end\nend\n",
      "export func main()\n  var A : matrix[2,2](float) = 1.0;\n  s = chol(A);\n"
      "  s = chol(A);\nend\n",
      "export func main()\n  const A : matrix[2,2](float) = 1.0;\n  A(0, :) = [1.0, 2.0];\nend\n",
      "export func main()\n  ivar i;\n  var v : vector[2](float);\n  i = 1;\nend\n",
  };
  for (const char* s : sources) {
    auto c = compile(s);
    ASSERT_FALSE(c->diagnostics.items().empty()) << s;
    EXPECT_EQ(c->diagnostics.items().front().message, plain) << s;
  }
}

// Vector types that differ only in orientation print alike but for one quote; the message
// names the orientations and suggests the transpose.
TEST(PortingMessages, OrientationMismatchIsNamed) {
  EXPECT_EQ(messages("export func main()\n"
                     "  var c : vector[3](float);\n"
                     "  var r = [1.0, 2.0, 3.0];\n"
                     "  c = r;\n"
                     "  r = c;\n"
                     "end\n"),
            (Lines{"4:7 type: cannot assign a row vector (vector[3](float)') to a column vector "
                   "target (vector[3](float)): transpose it with the ' operator",
                   "5:7 type: cannot assign a column vector (vector[3](float)) to a row vector "
                   "target (vector[3](float)'): transpose it with the ' operator"}));
  EXPECT_EQ(messages("export func main()\n"
                     "  var c : vector[3](float) = [1.0, 2.0, 3.0];\n"
                     "end\n"),
            (Lines{"2:30 type: cannot initialize a column vector variable (vector[3](float)) "
                   "with a row vector (vector[3](float)'): transpose it with the ' operator"}));
  // Types that differ in more than orientation keep the plain message.
  EXPECT_EQ(messages("export func main()\n"
                     "  var c : vector[2](float);\n"
                     "  c = [1.0, 2.0, 3.0];\n"
                     "end\n"),
            (Lines{"3:7 type: cannot assign a value of type 'vector[3](float)'' to a target of "
                   "type 'vector[2](float)'"}));
}

// A function named like an intrinsic is one error: its calls and maps are checked against
// the function as written, not against the intrinsic it cannot replace.
TEST(PortingMessages, RedefinedIntrinsicIsOneError) {
  EXPECT_EQ(messages("func inv(a : float) -> r : float\n"
                     "  r = 1.0 / a;\n"
                     "end\n"
                     "export func main()\n"
                     "  x = inv(2.0);\n"
                     "  print x + 1.0;\n"
                     "end\n"),
            (Lines{"1:6 redefinition: redefinition of intrinsic function 'inv'"}));
  EXPECT_EQ(messages("func inv4(A : matrix[4,4](float), eps : float) -> B : matrix[4,4](float)\n"
                     "  B = A;\n"
                     "end\n"
                     "export func main()\n"
                     "  var A : matrix[4,4](float) = 1.0;\n"
                     "  B = inv4(A, 1e-9);\n"
                     "end\n"),
            (Lines{"1:6 redefinition: redefinition of intrinsic function 'inv4'"}));
  EXPECT_EQ(messages("element P\n  x : float;\nend\n"
                     "extern ps : set{P};\n"
                     "func norm(p : P) -> r : vector[ps](float)\n"
                     "  r(p) = p.x;\n"
                     "end\n"
                     "export func main()\n"
                     "  ps.x = map norm to ps reduce +;\n"
                     "end\n"),
            (Lines{"5:6 redefinition: redefinition of intrinsic function 'norm'"}));
  // Calls that disagree with the function as written are still errors.
  EXPECT_EQ(messages("func inv(a : float) -> r : float\n"
                     "  r = 1.0 / a;\n"
                     "end\n"
                     "export func main()\n"
                     "  x = inv(2);\n"
                     "end\n"),
            (Lines{"1:6 redefinition: redefinition of intrinsic function 'inv'",
                   "5:11 type: expected argument of type 'float' but got an argument of type "
                   "'int'"}));
}

}  // namespace
}  // namespace simit::frontend
