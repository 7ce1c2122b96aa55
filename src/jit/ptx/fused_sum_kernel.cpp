// The fused-sum kernel (jit/ptx/fused_sum_kernel.h): its PTX, its host equivalent and its
// table of source blocks.
#include "jit/ptx/fused_sum_kernel.h"

#include "jit/ptx/gather_kernel.h"
#include "runtime/system_matrix.h"

namespace simit::jit::ptx {

namespace {

// Written by hand, as the gather kernel is (jit/ptx/gather_kernel.cpp): a product, an
// optional addition to 0.0 and a sum per component, each an explicit `.rn` operation that
// ptxas never fuses into an FMA, so the bits are runtime::add_into's. Under float32 the two
// roundings to binary32 are `cvt.rn.f32.f64` and back, as the host's static_cast<float>.
constexpr const char* kBody = R"(.visible .entry simit_fused_sum(
	.param .u64 simit_fused_sum_param_0,
	.param .u64 simit_fused_sum_param_1,
	.param .u64 simit_fused_sum_param_2,
	.param .f64 simit_fused_sum_param_3,
	.param .f64 simit_fused_sum_param_4,
	.param .u32 simit_fused_sum_param_5,
	.param .u32 simit_fused_sum_param_6,
	.param .u32 simit_fused_sum_param_7,
	.param .u32 simit_fused_sum_param_8
)
{
	.reg .pred 	%p<6>;
	.reg .b32 	%r<12>;
	.reg .b64 	%rd<8>;
	.reg .f64 	%fd<8>;
	.reg .f32 	%f<3>;

	// i = ctaid.x * ntid.x + tid.x; the threads past B's blocks do nothing.
	mov.u32 	%r1, %ctaid.x;
	mov.u32 	%r2, %ntid.x;
	mov.u32 	%r3, %tid.x;
	mad.lo.u32 	%r4, %r1, %r2, %r3;
	ld.param.u32 	%r5, [simit_fused_sum_param_5];
	setp.ge.u32 	%p1, %r4, %r5;
	@%p1 bra 	$L__done;
	ld.param.u64 	%rd1, [simit_fused_sum_param_0];
	cvta.to.global.u64 	%rd1, %rd1;
	ld.param.u64 	%rd2, [simit_fused_sum_param_1];
	cvta.to.global.u64 	%rd2, %rd2;
	ld.param.u64 	%rd3, [simit_fused_sum_param_2];
	cvta.to.global.u64 	%rd3, %rd3;
	ld.param.f64 	%fd1, [simit_fused_sum_param_3];
	ld.param.f64 	%fd2, [simit_fused_sum_param_4];
	ld.param.u32 	%r6, [simit_fused_sum_param_6];
	ld.param.u32 	%r7, [simit_fused_sum_param_7];
	ld.param.u32 	%r8, [simit_fused_sum_param_8];
	setp.ne.u32 	%p2, %r7, 0;
	setp.ne.u32 	%p3, %r8, 0;
	// j = from[i]; %p4: A has no block here.
	mul.wide.u32 	%rd4, %r4, 4;
	add.s64 	%rd4, %rd3, %rd4;
	ld.global.u32 	%r9, [%rd4];
	setp.lt.s32 	%p4, %r9, 0;
	// %rd5: &b[i * components]; %rd6: &a[j * components] (not read when j < 0).
	mul.wide.u32 	%rd5, %r4, %r6;
	shl.b64 	%rd5, %rd5, 3;
	add.s64 	%rd5, %rd1, %rd5;
	mul.wide.s32 	%rd6, %r9, %r6;
	shl.b64 	%rd6, %rd6, 3;
	add.s64 	%rd6, %rd2, %rd6;
	mov.u32 	%r10, 0;
$L__component:
	setp.ge.u32 	%p5, %r10, %r6;
	@%p5 bra 	$L__done;
	// t = beta * o (rounded to binary32 under float32).
	ld.global.f64 	%fd3, [%rd5];
	mul.rn.f64 	%fd4, %fd2, %fd3;
	@!%p3 bra 	$L__x;
	cvt.rn.f32.f64 	%f1, %fd4;
	cvt.f64.f32 	%fd4, %f1;
$L__x:
	// x = 0.0 where A has no block, else alpha * a (added to 0.0 for a union sum).
	mov.f64 	%fd5, 0d0000000000000000;
	@%p4 bra 	$L__sum;
	ld.global.f64 	%fd6, [%rd6];
	mul.rn.f64 	%fd5, %fd1, %fd6;
	@!%p2 bra 	$L__sum;
	add.rn.f64 	%fd5, %fd5, 0d0000000000000000;
$L__sum:
	add.rn.f64 	%fd7, %fd5, %fd4;
	@!%p3 bra 	$L__store;
	cvt.rn.f32.f64 	%f2, %fd7;
	cvt.f64.f32 	%fd7, %f2;
$L__store:
	st.global.f64 	[%rd5], %fd7;
	add.s64 	%rd5, %rd5, 8;
	add.s64 	%rd6, %rd6, 8;
	add.s32 	%r10, %r10, 1;
	bra.uni 	$L__component;
$L__done:
	ret;
}
)";

double to_binary32(double v) { return static_cast<double>(static_cast<float>(v)); }

}  // namespace

std::string fused_sum_ptx(const std::string& arch, const std::string& version) {
  return hand_written_module("The fused-sum kernel (simit: jit/ptx/fused_sum_kernel.h)", arch,
                             version, kBody);
}

void fused_sum_on_host(const FusedSumArgs& a, uint32_t first, uint32_t end) {
  const size_t n = a.components;
  for (uint32_t i = first; i < end && i < a.blocks; ++i) {
    double* o = a.b + static_cast<size_t>(i) * n;
    const int32_t j = a.from[i];
    for (size_t c = 0; c < n; ++c) {
      double t = a.beta * o[c];
      if (a.float32) t = to_binary32(t);
      double x = 0.0;
      if (j >= 0) {
        x = a.alpha * a.a[static_cast<size_t>(j) * n + c];
        if (a.zero_plus) x = x + 0.0;
      }
      const double sum = x + t;
      o[c] = a.float32 ? to_binary32(sum) : sum;
    }
  }
}

bool fused_sum_sources(const runtime::MatrixPattern& a, const runtime::MatrixPattern& b,
                       std::vector<int32_t>& from) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return false;
  from.assign(static_cast<size_t>(b.nnz()), -1);
  for (int r = 0; r < b.rows(); ++r) {
    int32_t i = a.row_ptr()[static_cast<size_t>(r)];
    const int32_t end = a.row_ptr()[static_cast<size_t>(r) + 1];
    for (int32_t k = b.row_ptr()[static_cast<size_t>(r)];
         k < b.row_ptr()[static_cast<size_t>(r) + 1] && i < end; ++k)
      if (a.col_idx()[static_cast<size_t>(i)] == b.col_idx()[static_cast<size_t>(k)])
        from[static_cast<size_t>(k)] = i++;
    if (i < end) return false;  // a block of A that B's row does not hold
  }
  return true;
}

}  // namespace simit::jit::ptx
