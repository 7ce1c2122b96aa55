// `simit run`: one exported function, arguments from the command line.
#include "commands/run_command.h"

#include <memory>
#include <new>
#include <optional>

#include "api/engine.h"
#include "api/stop_on_sigint.h"
#include "interp/operators.h"
#include "interp/printing.h"
#include "testing/literal.h"
#include "testing/value_match.h"

namespace simit::tools {

namespace ast = frontend::ast;
using frontend::Type;

namespace {

int usage(std::ostream& err, const std::string& message) {
  err << "simit run: " << message << "\n";
  return 1;
}

// The arguments as values of the parameters' types, or an error message.
bool convert_args(const ast::FuncDecl& f, const RunOptions& options,
                  std::vector<interp::Value>& values, std::string& error) {
  if (options.args.size() != f.params.size()) {
    error = "'" + f.name + "' takes " + std::to_string(f.params.size()) + " arguments but " +
            std::to_string(options.args.size()) + " were given";
    return false;
  }
  GenericSizes sizes;
  for (size_t i = 0; i < f.params.size(); ++i) {
    LiteralResult parsed = parse_literal(options.args[i]);
    if (!parsed.literal) {
      error = "argument " + std::to_string(i + 1) + ": " + parsed.error;  // it quotes the text
      return false;
    }
    const Type& want = *f.params[i].var->type;
    frontend::TypeRef got = literal_type(*parsed.literal);
    if (!type_matches(want, *got, sizes, false)) {
      error = "argument " + std::to_string(i + 1) + " has type '" + frontend::to_string(*got) +
              "' but parameter '" + f.params[i].name + "' has type '" + frontend::to_string(want) +
              "' (a column vector is written [1.0, 2.0]')";
      return false;
    }
    values.push_back(literal_value(*parsed.literal));
    if (options.float32) interp::round_to_float32(values.back());
  }
  return true;
}

bool is_column(const Type& t) {
  return t.kind == Type::Kind::Tensor && t.dims.size() == 1 && !t.row;
}

}  // namespace

int run_function(const RunOptions& options, std::ostream& out, std::ostream& err) {
  return run_function(options, RunHooks{}, out, err);
}

int run_function(const RunOptions& options, const RunHooks& hooks, std::ostream& out,
                 std::ostream& err) {
  std::shared_ptr<const api::CompiledProgram> c =
      hooks.program ? hooks.program : api::CompiledProgram::from_file(options.file);
  if (!c->ok()) {
    err << c->compilation()->diagnostics.render_all();
    return 1;
  }
  const ast::FuncDecl* f = c->find_func(options.func);
  if (!f) return usage(err, "no function named '" + options.func + "' in " + options.file);
  if (!f->exported) return usage(err, "'" + options.func + "' is not an exported function");
  std::vector<interp::Value> args;
  std::string error;
  if (!convert_args(*f, options, args, error)) return usage(err, error);
  api::EngineOptions run_options;
  run_options.float32 = options.float32;
  run_options.check_finite = options.check_finite;
  run_options.out = &out;
  run_options.trap = hooks.trap;
  if (std::string bad = executor_unavailable(options.executor); !bad.empty())
    return usage(err, bad);
  run_options.executor = options.executor;
  run_options.dump = &out;
  // --jit-stats: Ctrl-C stops the run with an error instead of ending the process, so that
  // the stats still print (a debugger's trap already stops it its own way).
  interp::Trap own_trap;
  std::optional<api::StopOnSigint> stop_on_sigint;
  if (options.jit_stats && !hooks.trap) {
    run_options.trap = &own_trap;
    stop_on_sigint.emplace(own_trap);
  }
  std::unique_ptr<api::Engine> engine;
  // Also after a run-time error, a NaN stop or an interrupt, when they are needed most: what
  // the JIT compiled up to there, after the error message.
  auto print_jit_stats = [&] {
    if (options.jit_stats && engine) engine->print_jit_stats(out);
  };
  try {
    engine = std::make_unique<api::Engine>(c, run_options);
    std::vector<interp::Value> results = engine->call(*f, std::move(args));
    for (size_t i = 0; i < results.size(); ++i)
      out << f->results[i].name << " = "
          << interp::literal_text(results[i], is_column(*f->results[i].var->type)) << "\n";
    print_jit_stats();
  } catch (const interp::RuntimeError& e) {
    out.flush();
    err << e.render();
    print_jit_stats();
    return 1;
  } catch (const std::bad_alloc&) {
    out.flush();
    err << "simit run: out of memory while running '" << f->name << "'\n";
    print_jit_stats();
    return 1;
  } catch (const std::exception& e) {  // never a user mistake: say so plainly
    err << "simit run: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace simit::tools
