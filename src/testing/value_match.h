// What the interpreter's executors need besides the interpreter: literals of `%@` directives
// and command lines as values, type matching with generic parameters bound on the way,
// and the comparison rules of TESTFORMAT.md §3.2 step 6.
#pragma once

#include <map>
#include <optional>
#include <string>

#include "frontend/ast.h"
#include "frontend/types.h"
#include "interp/value.h"
#include "literal.h"

namespace simit::tools {

// The sizes bound to generic parameters while matching argument types.
using GenericSizes = std::map<const frontend::ast::Variable*, int>;

// Whether a value of type `actual` may be passed where `wanted` is declared, binding
// generic dimensions of `wanted` to the sizes of `actual`. Vector orientation counts
// unless `ignore_orientation`.
bool type_matches(const frontend::Type& wanted, const frontend::Type& actual, GenericSizes& sizes,
                  bool ignore_orientation);

// The type and the value of a parsed literal.
frontend::TypeRef literal_type(const Literal& lit);
interp::Value literal_value(const Literal& lit);

// TESTFORMAT.md §3.2: int, bool and string components equal; floats equal or within
// relative 1e-3 (so an expected 0.0 needs an exact zero), complex parts likewise; with
// `abs_tolerance`, |a - b| <= tolerance instead of the relative rule. Shapes must agree.
bool values_match(const interp::Value& actual, const interp::Value& expected,
                  std::optional<double> abs_tolerance = std::nullopt);

}  // namespace simit::tools
