// The fused-sum kernel: `B = alpha A + beta B` in B's storage on the device (the fused matrix
// sum `A = M - s * K` of jit/matrix_sum.h, runtime::add_into's arithmetic), one thread per
// block of B, as PTX text; and the same computation on the host, which the emulated GPU
// executor runs over its "device" memory in place of the launch.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace simit::runtime {
class MatrixPattern;
}

namespace simit::jit::ptx {

// The name of the fused-sum kernel's `.entry`.
inline constexpr const char* kFusedSumEntry = "simit_fused_sum";

// The kernel's parameters, in order (device addresses, or host ones for fused_sum_on_host).
// Thread i < blocks computes, for each component c < components of block i of B, with
// o = b[i * components + c] and j = from[i] (A's block there, or -1 where A has none):
//   x = j < 0 ? 0.0 : (zero_plus ? 0.0 + alpha * a[j * components + c]
//                                : alpha * a[j * components + c])
//   b[i * components + c] = x + beta * o
// each operation rounded to binary64 (and, with float32, beta * o and the sum each rounded to
// binary32): runtime::add_into's bits, whose union sum adds A to 0.0 first.
struct FusedSumArgs {
  double* b = nullptr;
  const double* a = nullptr;
  const int32_t* from = nullptr;
  double alpha = 1.0;
  double beta = 1.0;
  uint32_t blocks = 0;
  uint32_t components = 1;
  uint32_t zero_plus = 0;
  uint32_t float32 = 0;
};

// The fused-sum kernel's module for `arch` and PTX ISA `version` ("" takes the defaults).
std::string fused_sum_ptx(const std::string& arch = "", const std::string& version = "");

// Threads [first, end) of the fused-sum kernel over `args`, on the calling thread.
void fused_sum_on_host(const FusedSumArgs& args, uint32_t first, uint32_t end);

// Per block of pattern `b`, the block of pattern `a` at the same row and column, or -1:
// FusedSumArgs::from. False when `a` has a block outside `b`'s pattern (or another shape).
bool fused_sum_sources(const runtime::MatrixPattern& a, const runtime::MatrixPattern& b,
                       std::vector<int32_t>& from);

}  // namespace simit::jit::ptx
