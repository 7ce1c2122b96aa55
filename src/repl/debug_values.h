// How the step debugger shows run-time values, and which values hold a NaN or an infinity.
#pragma once

#include <string>

#include "frontend/types.h"
#include "interp/value.h"

namespace simit::repl {

// One line: scalars and small tensors as literals (`[1.0, 0.0; 0.0, 1.0]`, floats exactly),
// large tensors as their shape and a summary, elements as `tets[17]`, endpoint tuples as
// `(verts[3], verts[8])`, sets and system matrices by their sizes. `type` (may be null)
// tells a column vector from a row vector.
std::string value_text(const interp::Value& v, const frontend::Type* type);

// False when a float or complex component of `v` (a scalar, a tensor or a system matrix) is
// a NaN or an infinity.
bool all_finite(const interp::Value& v);

}  // namespace simit::repl
