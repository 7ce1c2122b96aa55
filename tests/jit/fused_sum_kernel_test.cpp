// The fused-sum kernel (jit/ptx/fused_sum_kernel.h): its PTX rounds every operation on its
// own and ptxas accepts it; its host equivalent, which the emulated GPU runs, gives
// runtime::add_into's bits on one pattern and on a pattern within another, in binary64 and
// under float32; a block outside the target's pattern is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "jit/ptx/fused_sum_kernel.h"
#include "jit/ptx/ptx_check.h"
#include "jit/ptx/ptx_target.h"
#include "runtime/system_matrix.h"
#include "runtime/system_ops.h"

namespace simit::jit::ptx {
namespace {

// K: a 4 x 4 block tridiagonal pattern of 3 x 3 blocks; M: its diagonal.
runtime::PatternPtr tridiagonal() {
  return runtime::MatrixPattern::from_csr(4, 4, {0, 2, 5, 8, 10}, {0, 1, 0, 1, 2, 1, 2, 3, 2, 3});
}
runtime::PatternPtr diagonal() {
  return runtime::MatrixPattern::from_csr(4, 4, {0, 1, 2, 3, 4}, {0, 1, 2, 3});
}

// Values whose products and sums round, and signed zeros where they decide the sign: a zero
// of K times a negative factor is -0.0, and M's -0.0 added to 0.0 first is +0.0.
void fill(runtime::SystemMatrix& m, double seed) {
  double* v = m.values();
  for (size_t i = 0; i < m.value_count(); ++i) v[i] = std::sin(seed + 0.37 * i) * 1e3 / 3.0;
  v[0] = 0.0;
  v[4] = -0.0;
}

bool same_bits(const double* a, const double* b, size_t n) {
  return std::memcmp(a, b, n * sizeof(double)) == 0;
}

// K = alpha M + beta K by the kernel's host equivalent, in K's storage.
void by_kernel(const runtime::SystemMatrix& m, double alpha, runtime::SystemMatrix& k, double beta,
               bool float32, bool zero_plus) {
  std::vector<int32_t> from;
  ASSERT_TRUE(fused_sum_sources(m.pattern(), k.pattern(), from));
  FusedSumArgs a;
  a.b = k.values();
  a.a = m.values();
  a.from = from.data();
  a.alpha = alpha;
  a.beta = beta;
  a.blocks = static_cast<uint32_t>(k.pattern().nnz());
  a.components = static_cast<uint32_t>(k.block_size());
  a.zero_plus = zero_plus ? 1 : 0;
  a.float32 = float32 ? 1 : 0;
  fused_sum_on_host(a, 0, 3);  // threads apart, in any split, as the GPU's blocks run
  fused_sum_on_host(a, 3, 1000);
}

TEST(FusedSumKernel, ThePtxRoundsEveryOperationAndPtxasAcceptsIt) {
  const std::string p = fused_sum_ptx();
  EXPECT_NE(p.find(".target sm_90\n"), std::string::npos) << p;
  EXPECT_NE(p.find(".visible .entry simit_fused_sum("), std::string::npos) << p;
  for (const char* op : {"mul.rn.f64", "add.rn.f64", "cvt.rn.f32.f64"})
    EXPECT_NE(p.find(op), std::string::npos) << op;
  EXPECT_EQ(p.find("fma"), std::string::npos) << p;
  EXPECT_EQ(p.find("atom"), std::string::npos) << p;
  EXPECT_NE(fused_sum_ptx("sm_100", "8.6").find(".version 8.6\n.target sm_100\n"),
            std::string::npos);
  std::string why;
  const std::string ptxas = find_ptxas(why);
  if (ptxas.empty()) GTEST_SKIP() << "ptxas not found: " << why;
  std::string message;
  EXPECT_TRUE(assemble(ptxas, p, kDefaultGpuArch, message)) << message;
}

TEST(FusedSumKernel, OnTheHostItGivesAddIntosBitsOnAPatternWithinAnother) {
  for (bool float32 : {false, true}) {
    runtime::SystemMatrix m(diagonal(), 3, 3), k(tridiagonal(), 3, 3);
    fill(m, 1.0);
    fill(k, 2.0);
    m.values()[4] = -0.0;  // M's -0.0 against K's 0.0 at the same place
    k.values()[4] = 0.0;
    runtime::SystemMatrix want = k, got = k, unfused = k;
    const double beta = -(0.01 * 0.01);
    ASSERT_TRUE(runtime::add_into(m, 1.0, want, beta, nullptr, float32));
    by_kernel(m, 1.0, got, beta, float32, true);
    EXPECT_TRUE(same_bits(want.values(), got.values(), want.value_count())) << float32;
    EXPECT_FALSE(std::signbit(got.values()[4]));  // 0.0 + -0.0, then + -0.0
    // Without the addition to 0.0 the signed zero comes out otherwise: it is the union sum's.
    by_kernel(m, 1.0, unfused, beta, float32, false);
    EXPECT_TRUE(std::signbit(unfused.values()[4]));
  }
}

TEST(FusedSumKernel, OnTheHostItGivesAddIntosBitsOnOnePattern) {
  for (bool float32 : {false, true}) {
    const runtime::PatternPtr p = tridiagonal();
    runtime::SystemMatrix m(p, 3, 3), k(p, 3, 3);
    fill(m, 3.0);
    fill(k, 4.0);
    k.values()[4] = 0.0;  // times a negative factor: -0.0, added to M's -0.0
    runtime::SystemMatrix want = k, got = k;
    ASSERT_TRUE(runtime::add_into(m, 1.0, want, -2.5e-5, nullptr, float32));
    by_kernel(m, 1.0, got, -2.5e-5, float32, false);
    EXPECT_TRUE(same_bits(want.values(), got.values(), want.value_count())) << float32;
    EXPECT_TRUE(std::signbit(got.values()[4]));  // -0.0 + -0.0: no 0.0 added first
  }
}

TEST(FusedSumKernel, ABlockOutsideTheTargetsPatternIsRefused) {
  std::vector<int32_t> from;
  EXPECT_TRUE(fused_sum_sources(*diagonal(), *tridiagonal(), from));
  EXPECT_EQ(from, (std::vector<int32_t>{0, -1, -1, 1, -1, -1, 2, -1, -1, 3}));
  EXPECT_FALSE(fused_sum_sources(*tridiagonal(), *diagonal(), from));
  const auto other = runtime::MatrixPattern::from_csr(5, 5, {0, 1, 2, 3, 4, 5}, {0, 1, 2, 3, 4});
  EXPECT_FALSE(fused_sum_sources(*other, *tridiagonal(), from));
}

}  // namespace
}  // namespace simit::jit::ptx
