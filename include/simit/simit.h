// The Simit embedding API: build sets, load a program, bind and run its functions.
//
// Choices among the open points of API.md §8 (and how this API departs from the original):
//  1. Errors: load_string/load_file throw CompileError, whose what() is every diagnostic
//     rendered (file:line:col, the source line and a caret); Program::diagnostics() keeps
//     them as {line, column, category, message}. loadString/loadFile return the original's
//     codes (0, 1, 2) instead of throwing. Binding mismatches throw BindError listing every
//     problem by extern and field name; run-time errors of the program throw RuntimeError.
//     All derive from simit::Error.
//  2. Fields are typed at compile time (FieldRef<T, dims...>) and may also be described at
//     run time (Set::add_field(name, FieldType)).
//  3. Precision is a per-Program option (Options::float_size, default 8 = binary64); there is
//     no process-wide state. simit::init() only builds an Options value.
//  4. Batch construction: Set::add_many(n) returns the range of new handles.
//  5. Topology: elements are only appended; there is no remove(). run() notices that a bound
//     set grew since init() and re-initialises by itself.
//  6. Binding is per Function, by name (externs, parameters, results). Every declared field
//     must exist on the host set with the same component type and dimensions (extra host
//     fields are ignored), and an edge set's endpoint sets must be the very sets bound to the
//     externs its Simit type names (checked at init, when all are bound).
//     Host tensors (Tensor<T, dims...>) bound to externs, parameters and results are copied in
//     before and out after each run; sets are never copied (the interpreter reads and writes
//     the runtime storage inside simit::Set). Tensors whose type has set dimensions cannot be
//     bound; results of that kind are read after a run with Function::result()/matrix().
//     Only the externs the function actually uses (directly or through calls and maps) must
//     be bound; init() and run() name every one that is not.
//  7. No map/unmap: the interpreter works on the host storage directly; run() and runSafe()
//     are the same, mapArgs/unmapArgs are no-ops.
//  8. FFI (extern func) is not part of this API yet.
//  9. Assembled system matrices that are results are readable as SystemMatrixView (block CSR).
// 11. Execution is sequential in element order.
// 12. Grids are built by a Set constructor (points, extents), as in the original.
// Names: snake_case is the primary spelling (add_field, load_file, run); the original's
// camelCase names (addField, loadFile, runSafe, ...) are provided as aliases.
#pragma once

#include "simit/element.h"
#include "simit/program.h"
#include "simit/set.h"
#include "simit/tensor.h"
