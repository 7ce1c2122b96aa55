// `%!` tests run by the reference interpreter.
#include "interp_executor.h"

#include <sstream>

#include "frontend/diagnostics.h"
#include "interp/interpreter.h"
#include "interp/printing.h"
#include "value_match.h"

namespace simit::tools {

namespace ast = frontend::ast;
using frontend::Type;

namespace {

RunResult failed(std::string message) { return {RunResult::Status::Failed, std::move(message)}; }

bool is_column(const Type& t) {
  return t.kind == Type::Kind::Tensor && t.dims.size() == 1 && !t.row;
}

// Steps 1-4 of TESTFORMAT.md §3.2: the callee, its arity, and the literal types.
std::optional<RunResult> check_signature(const ast::Program& program, const ast::TestDecl& test,
                                         const ast::FuncDecl*& f) {
  f = test.callee ? test.callee : program.find_func(test.func);
  if (!f) return failed("attempting to test unknown function '" + test.func + "'");
  if (f->params.size() != test.args.size())
    return failed("'" + f->name + "' has " + std::to_string(f->params.size()) +
                  " parameters but the test passes " + std::to_string(test.args.size()) +
                  " arguments");
  if (f->results.size() != 1)
    return failed("'" + f->name + "' has " + std::to_string(f->results.size()) +
                  " results; only functions with exactly one result can be tested");
  GenericSizes sizes;
  for (size_t i = 0; i < test.args.size(); ++i) {
    const Type& want = *f->params[i].var->type;
    const Type& got = *test.args[i]->type;
    if (!type_matches(want, got, sizes, false))
      return failed("argument " + std::to_string(i + 1) + " has type '" + frontend::to_string(got) +
                    "' but parameter '" + f->params[i].name + "' has type '" +
                    frontend::to_string(want) + "'");
  }
  const Type& result = *f->results[0].var->type;
  if (!type_matches(result, *test.expected->type, sizes, true))
    return failed("the expected value has type '" + frontend::to_string(*test.expected->type) +
                  "' but the result '" + f->results[0].name + "' has type '" +
                  frontend::to_string(result) + "'");
  return std::nullopt;
}

}  // namespace

RunResult InterpExecutor::run_test(const ast::Program& program, const ast::TestDecl& test) {
  const ast::FuncDecl* f = nullptr;
  if (auto bad = check_signature(program, test, f)) return *bad;
  std::ostringstream discarded;
  interp::Options options = options_;
  if (!options.out) options.out = &discarded;
  try {
    interp::Interpreter interpreter(program, options);
    std::vector<interp::Value> args;
    for (const auto& a : test.args) args.push_back(interpreter.evaluate_constant(*a));
    interp::Value expected = interpreter.evaluate_constant(*test.expected);
    interp::Value actual = interpreter.call(*f, std::move(args)).at(0);
    if (values_match(actual, expected)) return {};
    bool column = is_column(*f->results[0].var->type);
    return failed(interp::literal_text(actual, column) +
                  " != " + interp::literal_text(expected, column));
  } catch (const interp::RuntimeError& e) {
    std::string text = e.render();
    if (!text.empty() && text.back() == '\n') text.pop_back();
    RunResult r{RunResult::Status::RuntimeError, text};
    r.line = e.line();
    return r;
  } catch (const std::exception& e) {
    return failed(std::string("the interpreter failed: ") + e.what());
  }
}

RunResult InterpExecutor::run_graph(const ast::Program&, const std::vector<GraphStep>&) {
  return {RunResult::Status::Skipped,
          "has graph directives; running them needs sets, which the interpreter does not "
          "support yet"};
}

}  // namespace simit::tools
