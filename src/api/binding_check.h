// Checks of host data against the program's types when it is bound: every problem is
// reported as one message naming the extern (or parameter) and the field concerned.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "frontend/ast.h"
#include "runtime/set.h"
#include "simit/tensor.h"

namespace simit::api {

// The field storage a Simit field type needs on the host (every level's dimensions,
// outermost first), or nothing when the type is not a fixed-size tensor.
std::optional<runtime::FieldType> field_type_for(const frontend::Type& type, int float_size);

// Kind (vertex, edge, grid), arity and fields of `set` against the set extern `var`.
std::vector<std::string> check_set(const frontend::ast::Variable& var, const runtime::Set& set,
                                   int float_size);

// The endpoint sets of `set` must be the sets bound to the externs `var`'s type names;
// `bound` gives the set bound to an extern (null when it is unbound: not reported here).
std::vector<std::string> check_endpoints(
    const frontend::ast::Variable& var, const runtime::Set& set,
    const std::function<const runtime::Set*(const frontend::ast::Variable&)>& bound);

// A host tensor against a tensor-typed extern, parameter or result; `what` names it
// ("extern 'dt'", "parameter 'x'").
std::vector<std::string> check_tensor(const std::string& what, const frontend::Type& type,
                                      const TensorSlot& tensor, int float_size);

// The host spelling of a field or tensor type, e.g. "double 3x3", "int".
std::string host_type_name(runtime::ComponentKind kind, bool single, const std::vector<int>& dims);

}  // namespace simit::api
