// `%!` tests and graph sections run through the engine.
#include "interp_executor.h"

#include <map>
#include <memory>
#include <span>
#include <sstream>
#include <utility>

#include "api/engine.h"
#include "frontend/diagnostics.h"
#include "interp/printing.h"
#include "interp/set_binding.h"
#include "runtime/set.h"
#include "value_match.h"

namespace simit::tools {

namespace ast = frontend::ast;
using frontend::Type;
using runtime::Tensor;

namespace {

RunResult failed(std::string message) { return {RunResult::Status::Failed, std::move(message)}; }

// A run stopped by a run-time error, with the line the runner checks `%@ error-line` against.
RunResult runtime_error_result(const interp::RuntimeError& e) {
  std::string text = e.render();
  if (!text.empty() && text.back() == '\n') text.pop_back();
  RunResult r{RunResult::Status::RuntimeError, text};
  r.line = e.line();
  // A difference `--check-jit` found is the JIT's failure, never the run-time error a
  // section may expect (the JIT reports it as a run-time error that starts so).
  if (e.message().starts_with("--check-jit:")) r.status = RunResult::Status::Failed;
  return r;
}

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
  api::EngineOptions options = options_;
  if (!options.out) options.out = &discarded;
  std::unique_ptr<api::Engine> engine;  // outlives the try: recorded after an error too
  RunResult result;
  try {
    engine = std::make_unique<api::Engine>(program, options);
    std::vector<interp::Value> args;
    for (const auto& a : test.args) args.push_back(engine->evaluate_constant(*a));
    interp::Value expected = engine->evaluate_constant(*test.expected);
    interp::Value actual = engine->call(*f, std::move(args)).at(0);
    bool column = is_column(*f->results[0].var->type);
    if (!values_match(actual, expected))
      result = failed(interp::literal_text(actual, column) +
                      " != " + interp::literal_text(expected, column));
  } catch (const interp::RuntimeError& e) {
    result = runtime_error_result(e);
  } catch (const std::exception& e) {
    result = failed(std::string("the interpreter failed: ") + e.what());
  }
  record(engine.get());
  return result;
}

JitRecord InterpExecutor::take_jit_record() { return std::exchange(jit_, JitRecord{}); }

void InterpExecutor::record(const api::Engine* engine) {
  if (!record_jit_ || !engine) return;
  std::vector<std::string> statuses = engine->jit_trace_statuses();
  if (statuses.empty()) return;  // a table without a trace says nothing
  std::ostringstream table;
  engine->print_jit_stats(table);
  jit_.tables += table.str();
  jit_.statuses.insert(jit_.statuses.end(), statuses.begin(), statuses.end());
}

namespace {

// Builds the sets and values of a section's graph directives and runs it (TESTFORMAT.md §7.3).
class GraphRun {
 public:
  GraphRun(const ast::Program& program, api::Engine& in, std::ostringstream& out)
      : program_(program), in_(in), out_(out) {}

  // An empty string when the step went well, else why the section fails.
  std::string step(const GraphStep& s) {
    return std::visit([&](const auto& a) { return apply(a); }, s.action);
  }

 private:
  const ast::Variable* global(const std::string& name) const {
    for (const ast::Variable* v : program_.globals)
      if (v && v->name == name && v->kind == ast::Variable::Kind::Extern) return v;
    return nullptr;
  }
  runtime::Set* set(const std::string& name) {
    auto it = sets_.find(name);
    return it == sets_.end() ? nullptr : it->second.get();
  }
  void add_fields(runtime::Set& s, const Type& t) {
    if (!t.element) return;
    for (const ast::FieldDecl& f : t.element->fields)
      if (s.field_index(f.name) < 0) s.add_field(f.name, interp::field_type_of(*f.type));
  }

  std::string apply(const SetDirective& d) {
    const ast::Variable* v = global(d.name);
    if (!v || v->type->kind != Type::Kind::Set) return "no extern set '" + d.name + "'";
    std::unique_ptr<runtime::Set> s;
    if (d.is_edge_set()) {
      std::vector<const runtime::Set*> ends;
      for (const std::string& e : d.endpoint_sets) {
        if (!set(e)) return "set '" + d.name + "' names endpoint set '" + e + "' before it exists";
        ends.push_back(set(e));
      }
      s = std::make_unique<runtime::Set>(d.name, ends);
      for (const auto& edge : d.edges) s->add(std::span<const int32_t>(edge.data(), edge.size()));
    } else {
      s = std::make_unique<runtime::Set>(d.name);
      s->add_many(d.size);
    }
    add_fields(*s, *v->type);
    in_.bind_set(*v, *s);
    sets_[d.name] = std::move(s);
    return "";
  }
  std::string apply(const GridDirective& d) {
    const ast::Variable* v = global(d.name);
    runtime::Set* points = set(d.point_set);
    if (!v || v->type->kind != Type::Kind::Set) return "no extern grid '" + d.name + "'";
    if (!points)
      return "grid '" + d.name + "' names point set '" + d.point_set + "' before it exists";
    auto g = std::make_unique<runtime::Set>(d.name, *points, d.extents);
    add_fields(*g, *v->type);
    in_.bind_set(*v, *g);
    sets_[d.name] = std::move(g);
    return "";
  }
  std::string apply(const FieldDirective& d) {
    runtime::Set* s = set(d.set);
    if (!s) return "field of unknown set '" + d.set + "'";
    int f = s->field_index(d.field);
    if (f < 0) return "set '" + d.set + "' has no field '" + d.field + "'";
    if (static_cast<int>(d.values.size()) != s->size())
      return "field " + d.set + "." + d.field + " lists " + std::to_string(d.values.size()) +
             " values for " + std::to_string(s->size()) + " elements";
    for (int k = 0; k < s->size(); ++k) {
      Tensor t = literal_value(d.values[k]).to_tensor();
      Tensor want = s->get(f, k);
      if (t.size() != want.size() || t.kind() != want.kind())
        return "value " + d.values[k].text + " does not fit field " + d.set + "." + d.field;
      t.reshape(want.shape());
      s->set(f, k, t);
    }
    return "";
  }
  std::string apply(const ValueDirective& d) {
    interp::Value value = literal_value(d.value);
    if (d.target == ValueDirective::Target::Argument) {
      args_[d.name] = std::move(value);
      return "";
    }
    const ast::Variable* v = global(d.name);
    if (!v) return "no extern tensor '" + d.name + "'";
    in_.set_global(*v, std::move(value));
    return "";
  }
  std::string apply(const RunDirective& d) {
    const ast::FuncDecl* f = program_.find_func(d.func);
    if (!f) return "no function '" + d.func + "' to run";
    for (int n = 0; n < d.times; ++n) {
      std::vector<interp::Value> args;
      for (const ast::Param& p : f->params) {
        auto it = args_.find(p.name);
        if (it == args_.end())
          return "no %@ arg for parameter '" + p.name + "' of '" + f->name + "'";
        interp::Value v = it->second;
        args.push_back(std::move(v));
      }
      std::vector<interp::Value> results = in_.call(*f, std::move(args));
      results_.clear();
      for (size_t i = 0; i < f->results.size() && i < results.size(); ++i)
        results_[f->results[i].name] = std::move(results[i]);
    }
    return "";
  }
  std::string apply(const ExpectDirective& d) {
    if (!d.is_field()) {
      interp::Value actual;
      if (auto it = results_.find(d.name); it != results_.end())
        actual = it->second;
      else if (const ast::Variable* v = global(d.name))
        actual = in_.global(*v);
      else
        return "nothing named '" + d.name + "' to check";
      if (d.values.size() != 1) return "expect " + d.name + " needs one value";
      interp::Value expected = literal_value(d.values[0]);
      if (actual.is_tensor() && expected.is_tensor() &&
          actual.tensor().size() == expected.tensor().size())
        expected.tensor().reshape(actual.tensor().shape());
      if (values_match(actual, expected, d.tolerance)) return "";
      return d.name + " is " + interp::literal_text(actual, false) + ", expected " +
             d.values[0].text;
    }
    runtime::Set* s = set(d.set);
    if (!s) return "expectation on unknown set '" + d.set + "'";
    int f = s->field_index(d.field);
    if (f < 0) return "set '" + d.set + "' has no field '" + d.field + "'";
    int first = d.element ? *d.element : 0;
    if (!d.element && static_cast<int>(d.values.size()) != s->size())
      return "expect " + d.set + "." + d.field + " lists " + std::to_string(d.values.size()) +
             " values for " + std::to_string(s->size()) + " elements";
    if (first < 0 || first + static_cast<int>(d.values.size()) > s->size())
      return "expect " + d.set + "." + d.field + ": element out of range";
    for (size_t i = 0; i < d.values.size(); ++i) {
      const int k = first + static_cast<int>(i);
      Tensor t = s->get(f, k);
      interp::Value actual =
          t.shape().is_scalar() ? interp::Value::component(t, 0) : interp::Value::of_tensor(t);
      interp::Value expected = literal_value(d.values[i]);
      if (expected.is_tensor() && actual.is_tensor() && expected.tensor().size() == t.size())
        expected.tensor().reshape(t.shape());
      if (!values_match(actual, expected, d.tolerance))
        return d.set + "." + d.field + "[" + std::to_string(k) + "] is " +
               interp::literal_text(actual, false) + ", expected " + d.values[i].text;
    }
    return "";
  }
  std::string apply(const ExpectOutputDirective& d) {
    if (out_.str() == d.text) return "";
    return "output was \"" + out_.str() + "\", expected \"" + d.text + "\"";
  }

  const ast::Program& program_;
  api::Engine& in_;
  std::ostringstream& out_;
  std::map<std::string, std::unique_ptr<runtime::Set>> sets_;
  std::map<std::string, interp::Value> args_, results_;
};

}  // namespace

RunResult InterpExecutor::run_graph(const ast::Program& program,
                                    const std::vector<GraphStep>& steps) {
  std::ostringstream output;
  api::EngineOptions options = options_;
  options.out = &output;
  std::unique_ptr<api::Engine> engine;  // outlives the try: recorded after an error too
  RunResult result;
  try {
    engine = std::make_unique<api::Engine>(program, options);
    GraphRun run(program, *engine, output);
    for (const GraphStep& s : steps) {
      std::string problem = run.step(s);
      if (!problem.empty()) {
        result = failed(problem);
        break;
      }
    }
    if (result.passed() && options_.out) *options_.out << output.str();
  } catch (const interp::RuntimeError& e) {
    result = runtime_error_result(e);
  } catch (const std::exception& e) {
    result = failed(std::string("the interpreter failed: ") + e.what());
  }
  record(engine.get());
  return result;
}

}  // namespace simit::tools
