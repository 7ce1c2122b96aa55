// The REPL session driven directly: inputs in, printed output compared.
#include "session.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace simit::repl {
namespace {

struct Repl {
  std::ostringstream out, err;
  Session s{out, err};
  std::string feed(const std::string& text) {
    out.str("");
    err.str("");
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) s.feed_line(line);
    return out.str() + err.str();
  }
};

TEST(Session, ExpressionPrintsValueAndType) {
  Repl r;
  EXPECT_EQ(r.feed("1.0 + 2.0"), "3.0 : float\n");
  EXPECT_EQ(r.feed("[1.0, 2.0]'"), "[1.0, 2.0]' : vector[2](float)\n");
}

TEST(Session, DeclarationsThenCalls) {
  Repl r;
  EXPECT_EQ(r.feed("func twice(x : float) -> (y : float)\n  y = 2.0 * x;\nend"), "");
  EXPECT_EQ(r.feed("twice(4.0)"), "8.0 : float\n");
}

TEST(Session, VariablesPersist) {
  Repl r;
  EXPECT_EQ(r.feed("x = 3.0;"), "");
  EXPECT_EQ(r.feed("x = x + 1.0;"), "");
  EXPECT_EQ(r.feed("x"), "4.0 : float\n");
}

TEST(Session, MultiLineBlocks) {
  EXPECT_FALSE(Session::is_complete("func f()\n"));
  EXPECT_FALSE(Session::is_complete("x = [1.0,\n"));
  EXPECT_TRUE(Session::is_complete("extern func g(x : float);\n"));
  Repl r;
  r.feed("x = 1.0;");
  EXPECT_EQ(r.feed("if x > 0.0\n  x = 5.0;\nend"), "");
  EXPECT_EQ(r.feed("x"), "5.0 : float\n");
}

TEST(Session, ErrorsLeaveTheSessionAlive) {
  Repl r;
  std::string e = r.feed("y + 1.0");
  EXPECT_NE(e.find("<repl>:1:1: error:"), std::string::npos) << e;
  e = r.feed("func bad(\n) -> (z : float)\n  z = q;\nend");
  EXPECT_NE(e.find("<repl>:3:7: error:"), std::string::npos) << e;
  EXPECT_EQ(r.feed("2 + 3"), "5 : int\n");
}

TEST(Session, Commands) {
  Repl r;
  EXPECT_NE(r.feed(":help").find(":load"), std::string::npos);
  EXPECT_EQ(r.feed(":h :type"), ":type EXPR      the type of an expression\n");
  EXPECT_EQ(r.feed(":type [1.0, 2.0]"), "vector[2](float)'\n");
  EXPECT_EQ(r.feed(":frob"), "unknown command ':frob' (:help lists the commands)\n");
  EXPECT_EQ(r.feed(":re"), "ambiguous command ':re': could be :reload :reset\n");
  r.feed("x = 1.0;");
  EXPECT_EQ(r.feed(":reset"), "");
  EXPECT_NE(r.feed("x").find("error"), std::string::npos);
  EXPECT_NE(r.feed(":load /nonexistent.sim").find("cannot read"), std::string::npos);
  EXPECT_EQ(r.s.completions(":rel"), std::vector<std::string>{":reload"});
  EXPECT_TRUE(r.s.feed_line(":help"));
  EXPECT_FALSE(r.s.feed_line(":q"));
}

TEST(Session, LoadAndReload) {
  std::string path = ::testing::TempDir() + "/repl_load.sim";
  {
    std::ofstream f(path);
    f << "func half(x : float) -> (y : float)\n  y = x / 2.0;\nend\n";
  }
  Repl r;
  EXPECT_EQ(r.feed(":load " + path), "loaded " + path + "\n");
  EXPECT_EQ(r.feed("half(3.0)"), "1.5 : float\n");
  EXPECT_EQ(r.feed(":reload"), "reloaded 1 file(s)\n");
  EXPECT_EQ(r.s.completions("hal"), std::vector<std::string>{"half"});
}

}  // namespace
}  // namespace simit::repl
