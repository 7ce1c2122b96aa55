// The intrinsic functions of LANGUAGE.md §9 and docs/intrinsics.md: one X-macro list of ids
// and names.
#pragma once

#include <optional>
#include <string_view>

namespace simit::frontend {

// Laid out by hand: clang-format cannot lay out this macro list stably.
// clang-format off
#define SIMIT_INTRINSICS(X)                                                          \
  X(Mod, "mod") X(Sin, "sin") X(Cos, "cos") X(Tan, "tan") X(Asin, "asin")            \
  X(Acos, "acos") X(Atan2, "atan2") X(Sqrt, "sqrt") X(Cbrt, "cbrt") X(Log, "log")    \
  X(Exp, "exp") X(Pow, "pow") X(Abs, "abs") X(Max, "max") X(Min, "min")              \
  X(Clock, "clock") X(StoreTime, "storeTime") X(Det, "det") X(Det2, "det2")          \
  X(Det4, "det4") X(Inv, "inv") X(Inv2, "inv2") X(Inv4, "inv4") X(Cross, "cross")    \
  X(Norm, "norm") X(Dot, "dot") X(CreateComplex, "createComplex")                    \
  X(ComplexGetReal, "complexGetReal") X(ComplexGetImag, "complexGetImag")            \
  X(ComplexNorm, "complexNorm") X(ComplexConj, "complexConj") X(Lu, "lu")            \
  X(LuSolve, "lusolve") X(LuMatSolve, "lumatsolve") X(LuFree, "lufree")              \
  X(Chol, "chol") X(LltSolve, "lltsolve") X(LltMatSolve, "lltmatsolve")              \
  X(CholFree, "cholfree") X(TriangularSolve, "triangularSolve")                      \
  X(Svd, "svd") X(Eig, "eig") X(Polar, "polar") X(ProjectSpd, "project_spd")         \
  X(ProjectSpdAbs, "project_spd_abs")
// clang-format on

enum class Intrinsic {
  None,
#define SIMIT_INTRINSIC_ENUM(id, name) id,
  SIMIT_INTRINSICS(SIMIT_INTRINSIC_ENUM)
#undef SIMIT_INTRINSIC_ENUM
};

// The intrinsic called `name`, or nullopt.
std::optional<Intrinsic> find_intrinsic(std::string_view name);
const char* intrinsic_name(Intrinsic id);

}  // namespace simit::frontend
