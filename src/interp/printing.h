// Text forms of values: the `print` / `println` format (LANGUAGE.md §7.6) and the literal
// form used in messages and by `simit run`.
#pragma once

#include <ostream>
#include <string>

#include "interp/value.h"

namespace simit::interp {

// Scalars: ints and bools (1/0) in decimal, floats like C's %g, complex as `<re,im>`,
// strings verbatim. A row vector prints on one line, space-separated; a column vector one
// component per line; a matrix one row per line; other tensors one component per line
// preceded by its index, e.g. `(0, 1, 1) 2.5` (blocked: `(0, 1)(1, 0) 2.5`). No line break
// follows the last line.
void print_value(std::ostream& out, const Value& v, bool row);

// `3`, `2.5`, `true`, `<1.0,-2.0>`, `"text"`, `[1, 2; 3, 4]`, `[1.5, 2.5]'` (a column), with
// floats in the shortest form that reads back exactly. Blocked tensors are shown in their
// unblocked form.
std::string literal_text(const Value& v, bool column);

}  // namespace simit::interp
