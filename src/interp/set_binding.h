// How host data reaches the interpreter: sets bound to extern set declarations (with the
// mapping from the element type's fields to the set's fields) and solver handles.
//
// Binding interface for hosts (the public API, `simit test`):
//   Interpreter::bind_set(extern_var, set)  binds a runtime::Set to an extern set
//       declaration; the set must carry every field of the element type with its exact
//       type (create them with field_type_of) and, for edge sets, endpoint sets that are
//       bound to the extern's endpoint declarations. Throws RuntimeError naming the
//       mismatch. The set must outlive the interpreter's use of it; rebinding is allowed.
//   Interpreter::set_global(extern_var, value)  binds an extern tensor (Value::of_tensor
//       or a scalar). Global vectors are dense tensors whose outer dimension is the set size.
//   Interpreter::call(func, args)  runs an exported function; set fields are read and
//       written in place; results are Values (system matrices as Value::Kind::Matrix).
//   Interpreter::patterns()  the registry of matrix patterns shared by every assembly.
#pragma once

#include <memory>
#include <variant>
#include <vector>

#include "frontend/ast.h"
#include "runtime/set.h"
#include "runtime/solvers.h"

namespace simit::interp {

struct SetBinding {
  runtime::Set* set = nullptr;
  const frontend::ast::ElementDecl* element = nullptr;
  std::vector<int> fields;  // per field of the element type: its index in `set`
  // Per field, its declared shape: the set stores blocks of blocks (`vector[2](vector[3](float))`)
  // with their dimensions run together (2x3), in the same component order.
  std::vector<runtime::Shape> field_shapes;
  // Per endpoint: the binding of its set, found on the first tuple read (bindings are only
  // ever added, so the first one found for a set stays the one found).
  std::vector<SetBinding*> endpoint_bindings;
};

// The storage type of an element field declared with type `t` (tensor without set dims).
runtime::FieldType field_type_of(const frontend::Type& t);

// The runtime component kind that stores values of scalar type `k`.
runtime::ComponentKind component_of(frontend::ScalarKind k);

// What `lu` and `chol` return; `lufree` / `cholfree` empty it.
struct SolverHandle {
  std::variant<std::monostate, runtime::LuFactor, runtime::CholeskyFactor> factor;
  int block_rows = 1;  // of the factorised matrix
};

}  // namespace simit::interp
