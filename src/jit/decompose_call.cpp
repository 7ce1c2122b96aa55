// simit_jit_decompose (jit/decompose_call.h): the compiled code's door to runtime/decompositions.
#include "jit/decompose_call.h"

#include <cstring>

#include "jit/loop_ir.h"
#include "runtime/decompositions.h"
#include "runtime/fault.h"

namespace simit::jit {

namespace {

double* put(double* out, const runtime::Tensor& t) {
  std::memcpy(out, t.floats(), t.size() * sizeof(double));
  return out + t.size();
}

}  // namespace

extern "C" int32_t simit_jit_decompose(int32_t fn, int32_t n, int32_t float32, const double* in,
                                       double* out) {
  runtime::Tensor a(runtime::ComponentKind::Float, runtime::Shape{n, n});
  std::memcpy(a.mutable_floats(), in, static_cast<size_t>(n) * n * sizeof(double));
  // The interpreter's tolerance for symmetry (Interpreter::symmetry_tolerance).
  const double tolerance = float32 ? 1e-4 : 1e-8;
  try {
    switch (static_cast<Decomposition>(fn)) {
      case Decomposition::Svd: {
        runtime::RotationSvd d = runtime::rotation_svd(a);
        put(put(put(out, d.u), d.s), d.v);
        return 0;
      }
      case Decomposition::Eig: {
        runtime::SymmetricEig d = runtime::symmetric_eig(a, tolerance);
        put(put(out, d.w), d.q);
        return 0;
      }
      case Decomposition::Polar: {
        runtime::PolarDecomposition d = runtime::polar_decomposition(a);
        put(put(out, d.r), d.s);
        return 0;
      }
      case Decomposition::ProjectSpd:
      case Decomposition::ProjectSpdAbs: {
        const auto mode = static_cast<Decomposition>(fn) == Decomposition::ProjectSpd
                              ? runtime::SpdProjection::Clamp
                              : runtime::SpdProjection::Absolute;
        put(out, runtime::project_spd(a, mode, tolerance));
        return 0;
      }
    }
  } catch (const runtime::Fault&) {
    return 1;
  }
  return 1;
}

}  // namespace simit::jit
