// The system tracer: lowers a while loop of system-level statements (a CG iteration) to a
// SystemTrace: scalar statements, passes over vector components and sparse products, with
// the interpreter's variables bound to its arrays, sizes and scalar slots.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "frontend/ast.h"
#include "interp/interpreter.h"
#include "jit/loop_ir.h"

namespace simit::jit {

// Where a system trace's operands live among the running function's variables.
struct SystemBinding {
  std::vector<const frontend::ast::Variable*> scalars;  // per scalar local
  std::vector<Ty> scalar_types;
  struct Array {
    const frontend::ast::Variable* var = nullptr;
    enum class Part : uint8_t { Vector, RowPtr, Cols, Values } part = Part::Vector;
  };
  std::vector<Array> arrays;  // per array slot
  struct Size {
    const frontend::ast::Variable* var = nullptr;
    bool rows = false;  // a matrix's block rows; else a vector's components
  };
  std::vector<Size> sizes;
  // Vectors the loop assigns that may have no value before it: created (zero) with the
  // shape of `like` before the kernel runs.
  std::vector<std::pair<const frontend::ast::Variable*, const frontend::ast::Variable*>> created;
};

struct TracedSystem {
  std::optional<SystemTrace> trace;
  std::string reason;
  SystemBinding binding;
};

TracedSystem trace_system(const frontend::ast::While& loop, interp::Interpreter& in);

}  // namespace simit::jit
