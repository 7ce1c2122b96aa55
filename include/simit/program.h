// Programs and compiled functions: load Simit source, compile an exported function, bind the
// host's sets and tensors to its externs, parameters and results, and run it.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "simit/executor.h"
#include "simit/set.h"
#include "simit/tensor.h"

namespace simit {

namespace api {
class CompiledProgram;
}
namespace scene {
class Stepper;
}
namespace runtime {
class SystemMatrix;
class Tensor;
}  // namespace runtime

// Settings of one Program and the Functions compiled from it (there is no process-wide
// configuration).
struct Options {
  // What runs the compiled functions (simit/executor.h): the interpreter by default; the JIT
  // (kind Jit) needs a build with -DSIMIT_WITH_LLVM=ON, and compile() refuses it otherwise.
  ExecutorChoice executor;
  // 8: Simit `float` is binary64 and float fields are `double` on the host; 4: Simit `float`
  // is rounded to binary32 and float fields are `float` on the host.
  int float_size = 8;
  // Stop with a run-time error at the first NaN or infinity produced.
  bool check_finite = false;
  // Where `print` writes; null means standard output.
  std::ostream* out = nullptr;
  // While run() runs, the first SIGINT (Ctrl-C) stops it at its next statement (compiled maps
  // between chunks of elements) and run() throws Interrupted; a second one does what SIGINT
  // did before. For hosts that keep going after an interrupt (Python's KeyboardInterrupt).
  bool stop_on_interrupt = false;
};

// Options from the original's `init(backend, floatSize)` spelling: "cpu" (the JIT),
// "interpreter", "jit" or "gpu"; 4 or 8. Throws Error on any other name, on "cpu", "jit" or
// "gpu" in a build without the JIT, and on "gpu" where no GPU opens (the reason given). It sets
// nothing globally: pass the result to Program.
[[nodiscard]] Options init(const std::string& backend = "cpu", int float_size = 8);

// One compile diagnostic; `rendered` is `file:line:col: error: message`, the line and a caret.
struct Diagnostic {
  int line = 0;
  int column = 0;
  std::string category;  // "lexical", "syntax", "semantic" or a finer semantic category
  std::string message;
  std::string rendered;
};

// The source did not compile (or could not be read); what() is every diagnostic, rendered.
class CompileError : public Error {
 public:
  CompileError(std::string text, std::vector<Diagnostic> diagnostics)
      : Error(std::move(text)), diagnostics_(std::move(diagnostics)) {}
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

 private:
  std::vector<Diagnostic> diagnostics_;
};

// A bind (or init) found the host data inconsistent with the program; one line per problem,
// each naming the extern (and field) concerned.
class BindError : public Error {
 public:
  explicit BindError(std::vector<std::string> problems);
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  std::vector<std::string> problems_;
};

// The program stopped with a run-time error; what() is `file:line:col: runtime error: ...`
// followed by the active calls.
class RuntimeError : public Error {
 public:
  RuntimeError(std::string text, int line) : Error(std::move(text)), line_(line) {}
  int line() const { return line_; }

 private:
  int line_;
};

// A run stopped by Ctrl-C (Options::stop_on_interrupt); what() names the statement it
// stopped at. The function can run again.
class Interrupted : public RuntimeError {
 public:
  using RuntimeError::RuntimeError;
};

class Function;

// A dense result of a run (Function::result): its components row-major, global vectors block
// after block, a scalar as one component. It shares the result, so copies are cheap.
class DenseResult {
 public:
  DenseResult() = default;

  ComponentKind kind() const;
  size_t size() const;
  // The dimensions, outermost first and every block level after its outer one (a global
  // vector of 3-vectors over 10 points: {10, 3}); empty for a scalar.
  std::vector<int> dims() const;
  // The components; the kind must match (ints for Int, floats for Float, ...).
  const int32_t* ints() const;
  const double* floats() const;
  const bool* bools() const;
  const double_complex* complexes() const;

 private:
  friend class Function;
  friend class scene::Stepper;
  explicit DenseResult(std::shared_ptr<const runtime::Tensor> t) : t_(std::move(t)) {}
  std::shared_ptr<const runtime::Tensor> t_;
};

// A read-only view of an assembled system matrix (block CSR): `rows` × `cols` blocks of
// `block_rows` × `block_cols` components: doubles (values()) for float matrices, int32s
// (ints(); 0 or 1 for bool) for int and bool ones, complexes() for complex ones. It shares the
// matrix, so it stays valid after later runs.
class SystemMatrixView {
 public:
  SystemMatrixView() = default;

  int rows() const;
  int cols() const;
  int block_rows() const;
  int block_cols() const;
  std::span<const int32_t> row_ptr() const;
  std::span<const int32_t> col_idx() const;
  ComponentKind kind() const;
  // The components: exactly one of these is non-empty (for a matrix with stored blocks).
  std::span<const double> values() const;
  std::span<const int32_t> ints() const;
  std::span<const double_complex> complexes() const;
  // Component (i, j) of the unblocked matrix (zero outside the pattern; ints converted;
  // throws for a complex matrix).
  double operator()(int64_t i, int64_t j) const;

 private:
  friend class Function;
  explicit SystemMatrixView(std::shared_ptr<const runtime::SystemMatrix> m) : m_(std::move(m)) {}
  std::shared_ptr<const runtime::SystemMatrix> m_;
};

class Program;

// Where a Function's runs spent their time, accumulated over runs (Function::stats()).
struct RunStats {
  int64_t runs = 0;
  double assembly_seconds = 0.0;  // wall time in outermost `map`/`apply` assemblies
  int64_t assemblies = 0;         // outermost maps and applies run
};

// One compiled function and its bindings. Bind every extern it uses (and its parameters),
// call init() once, then run() per step; sets are read and written in place.
class Function {
 public:
  Function();
  ~Function();
  Function(Function&&) noexcept;
  Function& operator=(Function&&) noexcept;

  bool defined() const { return impl_ != nullptr; }
  const std::string& name() const;

  // Binds a set extern; checks its kind, endpoints and fields against the program's type.
  void bind(const std::string& name, Set& set);
  void bind(const std::string& name, Set* set) { bind(name, *set); }
  // Binds an extern tensor, a parameter or a result (copied in before and out after each run).
  void bind(const std::string& name, const TensorSlot& tensor);
  template <Component T, int... dims>
  void bind(const std::string& name, Tensor<T, dims...>& tensor) {
    bind(name, tensor.slot());
  }
  template <Component T, int... dims>
  void bind(const std::string& name, Tensor<T, dims...>* tensor) {
    bind(name, tensor->slot());
  }

  // The host type the extern tensor, parameter or result `name` binds as (component kind,
  // dimensions with block levels after their outer one, binary32 floats under float size 4);
  // nullopt for a set, or a tensor whose size depends on a set. BindError for an unknown name.
  std::optional<FieldType> tensor_type(const std::string& name) const;

  // Names that still need a binding before init(): externs the function uses and parameters.
  std::vector<std::string> unbound() const;
  // Checks that everything is bound and consistent (endpoint sets are the sets bound to the
  // externs the program names), and prepares a run. Repeat after rebinding.
  void init();
  // Runs once. Initialises first when needed (never inited, rebound, or a bound set's
  // topology changed since init). Throws RuntimeError when the program fails.
  void run();

  // A result of the last run: a dense tensor (global vectors flat, block after block; scalars
  // as one component), or a system matrix.
  DenseResult result(const std::string& name) const;
  SystemMatrixView matrix(const std::string& name) const;

  // Time accounting of the runs since compile() or reset_stats() (cheap, always on): the rest
  // of a run's wall time is everything outside assembly (solves, vector algebra, control).
  RunStats stats() const;
  void reset_stats();
  // What runs the function: after init(), the choice its engine received; before, the
  // Options' choice it will receive.
  const ExecutorChoice& executor() const;

  // The spellings of the original API: on this in-process backend running is always safe
  // and there is nothing to map (API.md §8.7).
  void runSafe() { run(); }
  void mapArgs() {}
  void unmapArgs(bool = true) {}

 private:
  friend class Program;
  struct Impl;
  explicit Function(std::unique_ptr<Impl> impl);
  Impl& impl() const;
  std::unique_ptr<Impl> impl_;
};

// A loaded Simit program. Loading again replaces the source; functions compiled before keep
// the text they were compiled from.
class Program {
 public:
  explicit Program(Options options = {});
  ~Program();
  Program(Program&&) noexcept;
  Program& operator=(Program&&) noexcept;

  // Throw CompileError (with every diagnostic rendered) when the source has errors or the
  // file cannot be read; the diagnostics stay available below.
  void load_string(const std::string& source, const std::string& name = "<string>");
  void load_file(const std::string& path);
  // The original's status codes instead: 0 ok, 1 errors in the source, 2 unreadable file.
  int loadString(const std::string& source);
  int loadFile(const std::string& path);

  bool loaded() const;
  bool has_errors() const { return !diagnostics_.empty(); }
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }
  std::string diagnostics_text() const;
  bool hasErrors() const { return has_errors(); }

  // Exported functions, in declaration order.
  std::vector<std::string> function_names() const;
  std::vector<std::string> getFunctionNames() const { return function_names(); }
  // A runnable Function for a function with a body (normally an `export func`).
  Function compile(const std::string& name) const;

  const Options& options() const { return options_; }

 private:
  int load(const std::string& name, const std::string* text);
  Options options_;
  std::shared_ptr<const api::CompiledProgram> loaded_;
  std::vector<Diagnostic> diagnostics_;
};

}  // namespace simit
