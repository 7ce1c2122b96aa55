// Robustness: every function of every section of the language corpus, called with zero
// arguments of its parameter types, either returns or stops with a RuntimeError — never a
// crash, a hang (a hook bounds the statements) or another exception.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "interp/hook.h"
#include "test_util.h"

namespace simit::interp {
namespace {

namespace fs = std::filesystem;
namespace ast = frontend::ast;

struct Budget {};  // thrown by the hook when a call runs too long

class BudgetHook : public StatementHook {
 public:
  void before_statement(const ast::Stmt&, const ast::FuncDecl&, int, const Interpreter&) override {
    if (++count > 20000) throw Budget{};
  }
  int count = 0;
};

// Sections split at every `%%%` (TESTFORMAT.md §2); files not starting with it are whole.
std::vector<std::string> sections(const std::string& text) {
  if (text.rfind("%%%", 0) != 0) return {text};
  std::vector<std::string> out;
  for (size_t at = 0; at < text.size();) {
    size_t next = text.find("%%%", at + 3);
    if (next == std::string::npos) next = text.size();
    out.push_back(text.substr(at, next - at));
    at = next;
  }
  return out;
}

// Zero of a parameter type with every generic dimension taken as 2; false for types that
// need sets or elements.
bool zero_argument(const frontend::Type& t, Value& out) {
  if (t.kind == frontend::Type::Kind::Scalar) {
    switch (t.scalar) {
      case frontend::ScalarKind::Int: out = Value::of_int(0); break;
      case frontend::ScalarKind::Float: out = Value::of_float(0.0); break;
      case frontend::ScalarKind::Bool: out = Value::of_bool(false); break;
      case frontend::ScalarKind::Complex: out = Value::of_complex({0, 0}); break;
      case frontend::ScalarKind::String: out = Value::of_string(""); break;
    }
    return true;
  }
  if (t.kind != frontend::Type::Kind::Tensor) return false;
  std::vector<Shape> levels;
  const frontend::Type* cur = &t;
  for (; cur->kind == frontend::Type::Kind::Tensor; cur = cur->block.get()) {
    std::vector<int> dims;
    for (const auto& d : cur->dims) {
      if (d.kind == frontend::IndexSet::Kind::Set) return false;
      dims.push_back(d.kind == frontend::IndexSet::Kind::Fixed ? d.size : 2);
    }
    levels.push_back(Shape::of(dims));
  }
  Shape shape;
  for (auto it = levels.rbegin(); it != levels.rend(); ++it)
    shape = Shape::blocked(it->outer_dims(), shape);
  Value scalar;
  zero_argument(*cur, scalar);
  out = Value::zero(scalar.component_kind(), shape);
  return true;
}

TEST(CorpusSmoke, EveryFunctionRunsOrReportsARuntimeError) {
  // The budget that stops endless loops is a statement hook.
  if (!kStatementHook) GTEST_SKIP() << "built with SIMIT_STATEMENT_HOOK=OFF";
  int calls = 0, errors = 0;
  for (const auto& entry : fs::recursive_directory_iterator(SIMIT_SOURCE_DIR "/tests/lang")) {
    if (entry.path().extension() != ".sim" ||
        entry.path().string().find("illegal") != std::string::npos)
      continue;
    std::ifstream in(entry.path());
    std::stringstream ss;
    ss << in.rdbuf();
    for (const std::string& section : sections(ss.str())) {
      auto c = frontend::compile_source(entry.path().filename().string(), section);
      if (!c->ok()) continue;
      for (const auto& decl : c->program->decls) {
        const auto* f = decl->as<ast::FuncDecl>();
        if (!f || f->is_extern) continue;
        std::vector<Value> args;
        bool ok = true;
        for (const auto& p : f->params) {
          args.emplace_back();
          ok = ok && p.var && p.var->type && zero_argument(*p.var->type, args.back());
        }
        if (!ok) continue;
        BudgetHook hook;
        std::ostringstream sink;
        Options o;
        o.hook = &hook;
        o.out = &sink;
        Interpreter interp(*c->program, o);
        ++calls;
        try {
          interp.call(*f, args);
        } catch (const RuntimeError& e) {
          if (std::getenv("SIMIT_SMOKE_VERBOSE")) std::cout << e.message() << "\n";
          ++errors;
        } catch (const Budget&) {
        }
      }
    }
  }
  EXPECT_GT(calls, 300);
  std::cout << calls << " calls, " << errors << " run-time errors\n";
}

}  // namespace
}  // namespace simit::interp
