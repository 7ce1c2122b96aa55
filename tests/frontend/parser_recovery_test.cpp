// The parser's error recovery (one error per typo, deep nesting rejected, token soup
// terminating), the printers, and a print/parse round trip over the whole corpus.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "parser_support.h"

namespace simit::frontend {
namespace {

using namespace ast;
using namespace parser_support;

// ---------------------------------------------------------------------------
// Recovery (§3.6.10): one typo, one error; the rest still parses.

TEST(ParserRecovery, OneErrorPerTypo) {
  const char* cases[] = {
      "func f()\n  x = 1 +;\n  y = 2;\nend\nfunc g()\nend\n",
      "func f()\n  x = 1\n  if x\n    y = 2;\n  end\nend\nfunc g()\nend\n",
      "func f()\n  if 1 + * 2\n    y = 2;\n    while c\n    end\n  end\nend\nfunc g()\nend\n",
      "func f()\n  if c\n    y = 2;\nfunc g()\nend\n",
      "export func f\n  if c\n    y = 2;\n  end\nend\nfunc g()\nend\n",
      "func f()\n  %! f() == 1;\n  x = 1;\nend\nfunc g()\nend\n",
      "proc f()\n  print 1;\nend\nfunc g()\nend\n",
      "func f()\n  do\n    x = (1;\n  end while x\nend\nfunc g()\nend\n",
      "element E\n  a : Particle;\n  b : float;\nend\nfunc g()\nend\n",
      "func f()\n  x = [1, 2.0];\n  y = 3;\nend\nfunc g()\nend\n",
  };
  for (const char* text : cases) {
    auto p = parse_text(text);
    EXPECT_EQ(p->diags.size(), 1u) << text << "\n" << p->errors();
    EXPECT_NE(p->program->find_func("g"), nullptr) << text;
  }
}

TEST(ParserRecovery, GoodStatementsAroundAnErrorSurvive) {
  auto p = parse_text("func f()\n  a = 1;\n  b = ) 2;\n  c = 3;\nend\n");
  EXPECT_EQ(p->diags.size(), 1u);
  EXPECT_EQ(p->body().size(), 2u);
}

TEST(ParserRecovery, DeepNestingIsRejectedNotCrashed) {
  for (const std::string& text : {"func f()\n  x = " + std::string(100000, '(') + "1;\nend\n",
                                  "func f()\n  x = " + std::string(100000, '-') + "1;\nend\n",
                                  "func f()\n  x = 1" + std::string(100000, '\'') + ";\nend\n",
                                  "func f(x : " + repeat("vector(", 50000) + ")\nend\n"}) {
    auto p = parse_text(text);
    EXPECT_TRUE(p->diags.has_errors());
  }
  std::string nested_ifs;
  for (int i = 0; i < 5000; ++i) nested_ifs += "if c\n";
  auto p = parse_text("func f()\n" + nested_ifs + "\nend\n");
  EXPECT_TRUE(p->diags.has_errors());
  std::string sum = "1";
  for (int i = 0; i < 50000; ++i) sum += " + 1";
  p = parse_text("func f()\n  x = " + sum + ";\nend\n");
  ASSERT_TRUE(p->diags.has_errors());
  EXPECT_EQ(p->diags.items().front().message,
            "expression is too long: more than 1024 levels of chained operators and nesting");
  std::string brackets = std::string(20000, '[') + "1" + std::string(20000, ']');
  p = parse_text("func f()\n  x = " + brackets + ";\nend\n");
  EXPECT_TRUE(p->diags.has_errors());
}

TEST(ParserRecovery, ModerateNestingIsFine) {
  // A chain of prefix minus signs prints at the depth it parsed at, so it round-trips.
  std::string minus_chain = "func f(a : float)\n  b = " + std::string(200, '-') + "a;\nend\n";
  auto chain = parse_text(minus_chain);
  ASSERT_FALSE(chain->diags.has_errors());
  std::string once = print_source(*chain->program);
  auto again = parse_text(once);
  ASSERT_FALSE(again->diags.has_errors()) << once;
  EXPECT_EQ(print_source(*again->program), once);
  parse_ok("func f()\n  x = " + std::string(60, '(') + "1" + std::string(60, ')') + ";\nend\n");
  std::string sum = "1";
  for (int i = 0; i < 100; ++i) sum += " + 1";
  parse_ok("func f()\n  x = " + sum + ";\nend\n");
}

// Random token soup must terminate without crashing, and print_source and dump_ast must
// work on whatever was parsed.
TEST(ParserRecovery, RandomTokenSoupTerminates) {
  std::vector<std::string> words = {
      "func",   "end",    "if",      "elif", "else", "while",  "do",      "for",        "in",
      "var",    "const",  "ivar",    "map",  "to",   "reduce", "through", "apply",      "print",
      "extern", "export", "element", "set",  "grid", "tensor", "vector",  "matrix",     "float",
      "int",    "opaque", "inout",   "not",  "and",  "or",     "(",       ")",          "[",
      "]",      "{",      "}",       "<",    ">",    "=",      "==",      "+",          "-",
      "*",      "'",      ".",       ",",    ":",    ";",      "->",      "%!",         "x",
      "f",      "norm",   "1",       "0",    "2.0",  "\"s\"",  "true",    "<1.0, 2.0>", "\n"};
  std::mt19937 rng(12345);
  for (int round = 0; round < 3000; ++round) {
    std::string text;
    int n = static_cast<int>(rng() % 60);
    for (int i = 0; i < n; ++i) text += words[rng() % words.size()] + " ";
    auto p = parse_text(text);
    std::string src = print_source(*p->program);
    std::string tree = dump_ast(*p->program);
    EXPECT_EQ(dump_typed(*p->program), tree);
  }
}

// ---------------------------------------------------------------------------
// Printers

TEST(Printer, DumpAstShowsKindsAttributesAndLocations) {
  auto p = parse_ok("func f(x : float) -> y : float\n  y = -x + 2.0;\nend\n");
  std::string dump = dump_ast(*p->program);
  EXPECT_NE(dump.find("FuncDecl f @1:1"), std::string::npos) << dump;
  EXPECT_NE(dump.find("Param x @1:8"), std::string::npos) << dump;
  EXPECT_NE(dump.find("ScalarTypeExpr float @1:12"), std::string::npos) << dump;
  EXPECT_NE(dump.find("Assign targets=1 @2:3"), std::string::npos) << dump;
  EXPECT_NE(dump.find("      Binary + @2:7"), std::string::npos) << dump;
  EXPECT_NE(dump.find("        Unary - @2:7"), std::string::npos) << dump;
  EXPECT_NE(dump.find("FloatLit 2 @2:12"), std::string::npos) << dump;
}

TEST(Printer, DumpTypedShowsAnnotationsWhenPresent) {
  auto p = parse_ok("func f(x : float) -> y : float\n  y = x;\nend\n");
  EXPECT_EQ(dump_typed(*p->program), dump_ast(*p->program));
  auto* assign = const_cast<Block&>(p->body())[0]->as<Assign>();
  assign->value->type = make_scalar(ScalarKind::Float);
  std::string typed = dump_typed(*p->program);
  EXPECT_NE(typed.find("VarRef x : float @2:7"), std::string::npos) << typed;
  EXPECT_EQ(dump_ast(*p->program).find(" : float"), std::string::npos);
}

TEST(Printer, SourceRoundTripsTrickyForms) {
  const char* programs[] = {
      "func f(t : (a : E, b : E), u : (E * 2)) -> r : float\n"
      "  r = (t).x + (u)(0) + t.a.x + u(1).x;\nend\n",
      "func f()\n  x = -1 ^ 2;\n  y = (-1) ^ 2;\n  z = [1, 2; 3]';\n  w = -[1; 2, 3];\n"
      "  v = ([1.0, 2.0]')(0);\n  s = \"a\\\"b\\n\";\n  c = -<1.0, -0.0>;\nend\n",
      "func f()\n  if c\n    ;\n    -x;\n  end\n  for i in (a(1)) : n\n  end\nend\n",
      "func f()\n  do\n  end while c;\n  (x)(1) = 2;\nend\n",
      "extern s : set{E}(V * 0);\nfunc f()\n  y = foo<N>();\n  z = bar<N, 2>(1);\nend\n",
      "%! f(-1, [1.0, 2.0]', [[1, 2], [3, 4]]) == -<1.0, 2.0>;\n",
      "const big = 1e300;\nconst tiny = 2.5e-300;\nconst third = 0.3333333333333333;\n",
  };
  for (const char* text : programs) {
    auto p1 = parse_ok(text);
    std::string s1 = print_source(*p1->program);
    auto p2 = parse_ok(s1);
    std::string s2 = print_source(*p2->program);
    EXPECT_EQ(s1, s2) << text;
    EXPECT_EQ(dump_ast(*p1->program).size() > 0, true);
  }
}

// ---------------------------------------------------------------------------
// Round trip over the corpus (TESTFORMAT.md §2 sections)

std::vector<std::string> split_sections(const std::string& text) {
  if (text.rfind("%%%", 0) != 0) return {text};
  std::vector<std::string> sections;
  size_t at = 0;
  while (at < text.size()) {
    size_t next = text.find("%%%", at + 3);
    if (next == std::string::npos) next = text.size();
    sections.push_back(text.substr(at, next - at));
    at = next;
  }
  return sections;
}

TEST(ParserCorpus, PrintParsePrintIsStable) {
  namespace fs = std::filesystem;
  fs::path root = fs::path(SIMIT_SOURCE_DIR) / "tests" / "lang";
  if (!fs::exists(root)) GTEST_SKIP() << "no corpus at " << root;
  int checked = 0;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".sim") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    for (const std::string& section : split_sections(ss.str())) {
      if (section.rfind("%%%-", 0) == 0) continue;
      auto p1 = parse_text(section);
      if (p1->diags.has_errors()) continue;
      std::string s1 = print_source(*p1->program);
      auto p2 = parse_text(s1);
      std::string name =
          entry.path().filename().string() + " " + section.substr(0, section.find('\n'));
      ASSERT_FALSE(p2->diags.has_errors()) << name << "\n" << s1 << p2->errors();
      EXPECT_EQ(print_source(*p2->program), s1) << name;
      ++checked;
    }
  }
  EXPECT_GT(checked, 0);
}

TEST(ParserCorpus, AcceptedFilesParseWithoutSyntaxErrors) {
  namespace fs = std::filesystem;
  fs::path root = fs::path(SIMIT_SOURCE_DIR) / "tests" / "lang";
  if (!fs::exists(root)) GTEST_SKIP() << "no corpus at " << root;
  for (const auto& entry : fs::directory_iterator(root)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".sim") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    for (const std::string& section : split_sections(ss.str())) {
      if (section.rfind("%%%-", 0) == 0 || section.find("%@ error") != std::string::npos) continue;
      auto p = parse_text(section);
      EXPECT_FALSE(p->diags.has_errors())
          << entry.path().filename() << " " << section.substr(0, section.find('\n')) << "\n"
          << p->errors();
    }
  }
}

}  // namespace
}  // namespace simit::frontend
