// The system tracer: lowers a run of system-level statements (a CG function's set-up, its
// while loop and its residual, or the loop alone) to a SystemTrace: scalar statements, passes
// over vector components and sparse products, with the interpreter's variables bound to its
// arrays, sizes and scalar slots.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "frontend/ast.h"
#include "interp/exec_state.h"
#include "jit/loop_ir.h"

namespace simit::jit {

// Where a system trace's operands live among the running function's variables.
struct SystemBinding {
  std::vector<const frontend::ast::Variable*> scalars;  // per scalar local
  std::vector<Ty> scalar_types;
  struct Array {
    const frontend::ast::Variable* var = nullptr;  // the set for Field; null for Scratch
    // Field: the array of field `field` of the set `var` (`S.f`, in place). Scratch: a vector
    // of the trace's own (a product inside an expression, `b - A * x`), of the length
    // sizes[size], that no variable holds.
    enum class Part : uint8_t { Vector, RowPtr, Cols, Values, Field, Scratch } part = Part::Vector;
    int size = -1;   // Scratch: index into the sizes
    int field = -1;  // Field: the field's index among its element's fields
  };
  std::vector<Array> arrays;  // per array slot
  struct Size {
    const frontend::ast::Variable* var = nullptr;
    bool rows = false;  // a matrix's block rows; else a vector's components
    int field = -1;     // the components of this field of the set `var`
  };
  std::vector<Size> sizes;
  // Vectors the loop assigns that may have no value before it: created (zero) before the
  // kernel runs, with the shape of the vector `like`, or of field `like_field` of the set
  // `like` (`b = points.b`).
  struct Created {
    const frontend::ast::Variable* var = nullptr;
    const frontend::ast::Variable* like = nullptr;
    int like_field = -1;
  };
  std::vector<Created> created;
};

struct TracedSystem {
  std::optional<SystemTrace> trace;
  std::string reason;
  size_t failed_at = 0;  // without a trace: the statement (index into the run) that gave up
  SystemBinding binding;
};

// A statement the system tracer never compiles and the interpreter runs as it is: one that
// makes a system matrix (a sum or product of matrices) or solves directly (`A \ b`, the
// factorisation intrinsics). Runs of statements are offered without them.
bool matrix_statement(const frontend::ast::Stmt& s);

// "FIRST-LAST": the lines a run of statements covers.
std::string run_lines(const std::vector<const frontend::ast::Stmt*>& run);

// Traces consecutive statements of one block (system-level ones; at most one while loop),
// reading the shapes of vectors and matrices from the interpreter's variables. Under
// `float32` every operator, call and literal is rounded to binary32, as the interpreter's
// float32 mode rounds them (docs/arithmetic.md).
TracedSystem trace_system(const std::vector<const frontend::ast::Stmt*>& run, interp::ExecState& in,
                          bool float32 = false);

}  // namespace simit::jit
