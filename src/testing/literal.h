// Literal values written in `%@` directives, parsed with the literal grammar of
// LANGUAGE.md §3.4 and the folding rules of §6.2.6 (prefix signs, `'` on order-1 literals).
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "frontend/types.h"

namespace simit::tools {

// A scalar or dense tensor literal, kept with its type so that an executor can compare
// it with a parameter, field or result type.
struct Literal {
  frontend::ScalarKind kind = frontend::ScalarKind::Int;
  std::vector<int> shape;  // empty: a scalar; otherwise outermost dimension first
  bool column = false;     // an order-1 literal with `'` applied (it is a row otherwise)
  // Components in row-major order, in the vector that matches `kind`; bools as 0/1 ints.
  std::vector<long long> ints;
  std::vector<double> floats;
  std::vector<std::complex<double>> complexes;
  std::string string_value;  // String (escapes applied)
  std::string text;          // as written, for messages

  bool is_scalar() const { return shape.empty(); }
  size_t size() const;  // number of components (1 for scalars)
};

struct LiteralResult {
  std::optional<Literal> literal;
  std::string error;  // set when `literal` is empty
};

// A literal's tensors have at most Shape::kMaxRank dimensions; the reader stops well before
// a nesting deep enough to exhaust the stack.
inline constexpr int kMaxLiteralDepth = 64;

// Parses one whole literal; anything left over is an error.
LiteralResult parse_literal(std::string_view text);

// Splits `text` at commas outside brackets, angle brackets and quotes and trims each
// part; an all-blank text gives no parts.
std::vector<std::string> split_top_level(std::string_view text, char separator = ',');

}  // namespace simit::tools
