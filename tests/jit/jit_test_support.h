// What the JIT's tests against the interpreter share (tests/jit/jit_*_test.cpp): bit-for-bit
// comparisons of values, the line of a text in a source, and the matrix of a chain of links.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>

#include "api/engine.h"

namespace simit::jit::test_support {

namespace ast = frontend::ast;
using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;
using interp::Value;

// Bit-for-bit equality of two doubles arrays.
inline void expect_same_bits(const double* a, const double* b, size_t n, const std::string& what) {
  for (size_t i = 0; i < n; ++i)
    EXPECT_EQ(std::memcmp(&a[i], &b[i], sizeof(double)), 0)
        << what << "[" << i << "]: " << a[i] << " vs " << b[i];
}

// Matrices on one pattern compare value by value; a JIT result on a specialised pattern
// (fewer blocks, jit/specialise.h) compares as the dense matrix it means, entry by entry.
inline void expect_same(const Value& a, const Value& b, const std::string& what) {
  ASSERT_EQ(a.kind(), b.kind()) << what;
  if (a.kind() == Value::Kind::Matrix) {
    const runtime::SystemMatrix &x = *a.matrix(), &y = *b.matrix();
    if (x.shared_pattern() == y.shared_pattern()) {
      expect_same_bits(x.values(), y.values(), x.value_count(), what);
      return;
    }
    EXPECT_LE(y.pattern().nnz(), x.pattern().nnz()) << what;
    for (int64_t i = 0; i < x.scalar_rows(); ++i)
      for (int64_t j = 0; j < x.scalar_cols(); ++j) {
        const double u = x.component(i, j), v = y.component(i, j);
        EXPECT_TRUE(std::memcmp(&u, &v, sizeof u) == 0 || (u == 0.0 && v == 0.0))
            << what << "(" << i << ", " << j << "): " << u << " vs " << v;
      }
  } else {
    ASSERT_EQ(a.tensor().size(), b.tensor().size()) << what;
    expect_same_bits(a.tensor().floats(), b.tensor().floats(), a.tensor().size(), what);
  }
}

// The 1-based line of the first line of `text` that contains `what`.
inline int line_of(const std::string& s, const std::string& what) {
  const size_t at = s.find(what);
  return 1 + static_cast<int>(std::count(s.begin(), s.begin() + static_cast<long>(at), '\n'));
}

// The matrix of a chain of links between points (springs and a diagonal), for the solver
// tests: the program declares Point (with b and d), Link (with k), points and links.
inline const char* const kChainMatrix = R"(
func stiffness(l : Link, p : (Point * 2)) -> A : matrix[points,points](float)
  A(p(0), p(0)) = l.k;
  A(p(1), p(1)) = l.k;
  A(p(0), p(1)) = -0.5 * l.k;
  A(p(1), p(0)) = -0.5 * l.k;
end

func diagonal(q : Point) -> D : matrix[points,points](float)
  D(q, q) = q.d;
end
)";

}  // namespace simit::jit::test_support
