// The gather kernel (jit/ptx/gather_kernel.h): its PTX and its host equivalent.
#include "jit/ptx/gather_kernel.h"

#include <sstream>

#include "jit/ptx/ptx_target.h"
#include "runtime/sum_rounding.h"

namespace simit::jit::ptx {

namespace {

// Written by hand rather than through LLVM's NVPTX back end: twelve loads, one addition (under
// --float32 rounded to binary32 by two conversions) and a store in two loops, with no math function
// to link. The text says outright what runs (each addition an `add.rn.f64`, which ptxas never fuses
// or reorders), needs no LLVM context per executor, and is what a fake driver sees loaded.
//
// Thread i owns block block[i] (no other thread writes it). For each component c it loads the
// block's value after the map's launch, adds the deferred blocks' component c in the order of
// k[start[i] ..] and stores the sum: per component the sequence of additions finish performs
// (it loops over deferred blocks outside and components inside, but components never mix), so
// the bits are finish's; the accumulator stays in a register in between.
constexpr const char* kBody = R"(.visible .entry simit_gather(
	.param .u64 simit_gather_param_0,
	.param .u64 simit_gather_param_1,
	.param .u64 simit_gather_param_2,
	.param .u64 simit_gather_param_3,
	.param .u64 simit_gather_param_4,
	.param .u32 simit_gather_param_5,
	.param .u32 simit_gather_param_6,
	.param .u32 simit_gather_param_7
)
{
	.reg .pred 	%p<5>;
	.reg .b32 	%r<14>;
	.reg .f32 	%f<2>;
	.reg .b64 	%rd<19>;
	.reg .f64 	%fd<3>;

	// i = ctaid.x * ntid.x + tid.x; the threads past the gathered blocks do nothing.
	mov.u32 	%r1, %ctaid.x;
	mov.u32 	%r2, %ntid.x;
	mov.u32 	%r3, %tid.x;
	mad.lo.u32 	%r4, %r1, %r2, %r3;
	ld.param.u32 	%r5, [simit_gather_param_5];
	setp.ge.u32 	%p1, %r4, %r5;
	@%p1 bra 	$L__done;
	ld.param.u64 	%rd1, [simit_gather_param_0];
	cvta.to.global.u64 	%rd1, %rd1;
	ld.param.u64 	%rd2, [simit_gather_param_1];
	cvta.to.global.u64 	%rd2, %rd2;
	ld.param.u64 	%rd3, [simit_gather_param_2];
	cvta.to.global.u64 	%rd3, %rd3;
	ld.param.u64 	%rd4, [simit_gather_param_3];
	cvta.to.global.u64 	%rd4, %rd4;
	ld.param.u64 	%rd5, [simit_gather_param_4];
	cvta.to.global.u64 	%rd5, %rd5;
	ld.param.u32 	%r6, [simit_gather_param_6];
	// %p4: --float32, each sum rounded to binary32 and widened again (exactly).
	ld.param.u32 	%r13, [simit_gather_param_7];
	setp.ne.u32 	%p4, %r13, 0;
	// b = block[i], j0 = start[i], j1 = start[i + 1].
	mul.wide.u32 	%rd6, %r4, 4;
	add.s64 	%rd7, %rd3, %rd6;
	ld.global.u32 	%r7, [%rd7];
	add.s64 	%rd8, %rd4, %rd6;
	ld.global.u32 	%r8, [%rd8];
	ld.global.u32 	%r9, [%rd8+4];
	// %rd10: &values[b * components + c]; %rd11: &k[j0].
	mul.wide.u32 	%rd9, %r7, %r6;
	shl.b64 	%rd9, %rd9, 3;
	add.s64 	%rd10, %rd1, %rd9;
	mul.wide.u32 	%rd11, %r8, 4;
	add.s64 	%rd11, %rd5, %rd11;
	mov.u32 	%r10, 0;
$L__component:
	setp.ge.u32 	%p2, %r10, %r6;
	@%p2 bra 	$L__done;
	ld.global.f64 	%fd1, [%rd10];
	// %rd12: &k[j]; %rd13: &deferred[c].
	mov.u64 	%rd12, %rd11;
	mov.u32 	%r11, %r8;
	mul.wide.u32 	%rd13, %r10, 8;
	add.s64 	%rd13, %rd2, %rd13;
$L__deferred:
	setp.ge.s32 	%p3, %r11, %r9;
	@%p3 bra 	$L__store;
	ld.global.u32 	%r12, [%rd12];
	mul.wide.u32 	%rd14, %r12, %r6;
	shl.b64 	%rd14, %rd14, 3;
	add.s64 	%rd15, %rd13, %rd14;
	ld.global.f64 	%fd2, [%rd15];
	add.rn.f64 	%fd1, %fd1, %fd2;
	@%p4 cvt.rn.f32.f64 	%f1, %fd1;
	@%p4 cvt.f64.f32 	%fd1, %f1;
	add.s64 	%rd12, %rd12, 4;
	add.s32 	%r11, %r11, 1;
	bra.uni 	$L__deferred;
$L__store:
	st.global.f64 	[%rd10], %fd1;
	add.s64 	%rd10, %rd10, 8;
	add.s32 	%r10, %r10, 1;
	bra.uni 	$L__component;
$L__done:
	ret;
}
)";

}  // namespace

std::string hand_written_module(const std::string& what, const std::string& arch,
                                const std::string& version, const char* body) {
  std::ostringstream out;
  out << "//\n// " << what << "\n//\n\n"
      << ".version " << (version.empty() ? kDefaultPtxVersion : version) << "\n"
      << ".target " << (arch.empty() ? kDefaultGpuArch : arch) << "\n"
      << ".address_size 64\n\n"
      << body;
  return out.str();
}

std::string gather_ptx(const std::string& arch, const std::string& version) {
  return hand_written_module(
      "The gather kernel of a deferred assembly (simit: jit/ptx/gather_kernel.h)", arch, version,
      kBody);
}

void gather_on_host(const GatherArgs& a, uint32_t first, uint32_t end) {
  const size_t n = a.components;
  for (uint32_t i = first; i < end && i < a.blocks; ++i) {
    double* to = a.values + static_cast<size_t>(a.block[i]) * n;
    for (size_t c = 0; c < n; ++c) {
      double sum = to[c];
      for (int32_t j = a.start[i]; j < a.start[i + 1]; ++j) {
        sum += a.deferred[static_cast<size_t>(a.k[j]) * n + c];
        if (a.round32) sum = runtime::Binary32Sums::r(sum);
      }
      to[c] = sum;
    }
  }
}

std::string ptx_directive(const std::string& ptx, const std::string& directive) {
  std::istringstream in(ptx);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string word, operand;
    if (!(words >> word) || word != directive || !(words >> operand)) continue;
    if (const size_t comma = operand.find(','); comma != std::string::npos) operand.resize(comma);
    return operand;
  }
  return "";
}

}  // namespace simit::jit::ptx
