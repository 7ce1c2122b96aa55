// Per-element expressions of a scene file: arithmetic and comparisons over the element's
// position x, y, z (a vertex's coordinates, or an element's centroid), e.g. "y < 1e-4".
#pragma once

#include <cstddef>
#include <memory>
#include <string>

namespace simit::scene {

// Grammar (loosest first): `or` (also ||), `and` (&&), `not` (!), one comparison
// (< <= > >= == !=), + -, * /, unary -, ^ (right-associative), then numbers, x, y, z, pi,
// xmin xmax ymin ymax zmin zmax (the mesh's bounding box), parentheses and the functions sqrt abs
// sin cos tan exp log floor ceil min max. Comparisons and logic give 1 or 0. Limits that keep a
// hostile expression from exhausting the stack or the memory: its length in characters, and its
// nesting (parentheses, calls, prefix operators and `^` each count a level; a flat chain such as a
// + b + ... + z does not).
inline constexpr size_t kMaxExprLength = 65536;
inline constexpr int kMaxExprDepth = 256;

class PositionExpr {
 public:
  struct Node;
  // Throws std::invalid_argument("column N: ...") when the text is not an expression.
  explicit PositionExpr(const std::string& text);
  ~PositionExpr();
  PositionExpr(PositionExpr&&) noexcept;
  PositionExpr& operator=(PositionExpr&&) noexcept;

  // p: the element's position; lo, hi: the corners of the mesh's bounding box.
  double eval(const double p[3], const double lo[3], const double hi[3]) const;

 private:
  std::unique_ptr<Node> root_;
};

}  // namespace simit::scene
