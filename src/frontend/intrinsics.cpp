// Names and signatures of the intrinsic functions (LANGUAGE.md §9).
#include "frontend/intrinsics.h"

#include <optional>

#include "frontend/op_typing.h"

namespace simit::frontend {

namespace {

struct IntrinsicEntry {
  Intrinsic id;
  const char* name;
};

constexpr IntrinsicEntry kIntrinsics[] = {
#define SIMIT_INTRINSIC_ENTRY(id, name) {Intrinsic::id, name},
    SIMIT_INTRINSICS(SIMIT_INTRINSIC_ENTRY)
#undef SIMIT_INTRINSIC_ENTRY
};

}  // namespace

std::optional<Intrinsic> find_intrinsic(std::string_view name) {
  for (const IntrinsicEntry& e : kIntrinsics)
    if (name == e.name) return e.id;
  return std::nullopt;
}

const char* intrinsic_name(Intrinsic id) {
  for (const IntrinsicEntry& e : kIntrinsics)
    if (e.id == id) return e.name;
  return "<none>";
}

namespace {

constexpr ScalarKind F = ScalarKind::Float;

std::string quoted(const Type& t) { return "'" + to_string(t) + "'"; }

TypeRef flt() { return make_scalar(F); }

TypeRef dense(std::vector<int> sizes) {
  std::vector<IndexSet> dims;
  for (int n : sizes) dims.push_back(IndexSet::fixed(n));
  return make_tensor(std::move(dims), flt());
}

bool is_numeric(ScalarKind k) {
  return k == ScalarKind::Int || k == ScalarKind::Float || k == ScalarKind::Complex;
}

bool numeric_of_order(const Type& t, int order) {
  return t.is_tensor() && t.order() == order && is_numeric(t.component());
}

// The state of one call: its arguments, the generic parameters and what binds them.
struct Call {
  Intrinsic id;
  const std::vector<const Type*>& args;
  std::vector<const char*> params;  // generic parameter names
  std::vector<bool> bound;
  std::vector<IndexSet>& bindings;

  std::string name() const { return intrinsic_name(id); }
  void bind(size_t i, const IndexSet& s) {
    if (i < bound.size() && !bound[i]) {  // first binding wins
      bindings[i] = s;
      bound[i] = true;
    }
  }
  Typing fail(SemanticKind k, std::string msg) const { return Typing::failure(k, std::move(msg)); }
};

// The ordinary argument check of §10.4 against a fixed parameter type.
Typing expect_arg(const Call& c, size_t i, const Type& expected) {
  const Type& got = *c.args[i];
  if (types_equal(expected, got)) return Typing::success(flt());
  return c.fail(SemanticKind::Type, "expected argument of type " + quoted(expected) +
                                        " but got an argument of type " + quoted(got) +
                                        " in call to function '" + c.name() + "'");
}

// A call whose parameters all have fixed types.
Typing fixed_signature(const Call& c, const std::vector<TypeRef>& params, TypeRef result) {
  for (size_t i = 0; i < params.size(); ++i) {
    Typing t = expect_arg(c, i, *params[i]);
    if (!t.ok()) return t;
  }
  return Typing::success(std::move(result));
}

Typing unresolved_check(const Call& c) {
  for (size_t i = 0; i < c.bound.size(); ++i)
    if (!c.bound[i])
      return c.fail(SemanticKind::GenericUnresolved,
                    std::string("unable to resolve type parameter '") + c.params[i] +
                        "' for call to function '" + c.name() + "'");
  return Typing::success(flt());
}

Typing expect_float_component(const Call& c, const Type& t, const char* what) {
  if (t.component() == F) return Typing::success(flt());
  return c.fail(SemanticKind::Type, std::string("expected a ") + what + " of float components " +
                                        "in call to function '" + c.name() + "' but got " +
                                        quoted(t));
}

Typing type_norm(const Call& c) {
  const Type& v = *c.args[0];
  if (!numeric_of_order(v, 1))
    return c.fail(SemanticKind::Type,
                  "expected a numeric vector as argument but got an argument of type " + quoted(v));
  Typing f = expect_float_component(c, v, "vector");
  return f.ok() ? Typing::success(flt()) : f;
}

// Equal order-1 types, read without orientation at every blocking level.
bool same_vector_shape(const Type& a, const Type& b) {
  if (a.kind != b.kind) return false;
  if (a.kind != Type::Kind::Tensor) return types_equal(a, b);
  return a.dims == b.dims && a.block && b.block && same_vector_shape(*a.block, *b.block);
}

Typing type_dot(const Call& c) {
  const Type& a = *c.args[0];
  const Type& b = *c.args[1];
  std::string msg =
      "cannot call function 'dot' on arguments of type " + quoted(a) + " and type " + quoted(b);
  if (!numeric_of_order(a, 1) || !numeric_of_order(b, 1) || a.component() != b.component())
    return c.fail(SemanticKind::Type, msg);
  if (!same_vector_shape(a, b)) return c.fail(SemanticKind::Type, msg);
  Typing f = expect_float_component(c, a, "vector");
  return f.ok() ? Typing::success(flt()) : f;
}

// lu, chol: `<N>(A : matrix[N,N](float)) -> opaque`; only the kind of `A` is checked.
Typing type_factorize(Call& c) {
  const Type& a = *c.args[0];
  if (!numeric_of_order(a, 2))
    return c.fail(SemanticKind::Type,
                  "expected a numeric matrix as argument but got an argument of type " + quoted(a));
  Typing f = expect_float_component(c, a, "matrix");
  if (!f.ok()) return f;
  c.bind(0, a.dims[0]);
  return Typing::success(make_opaque());
}

Typing expect_opaque(const Call& c) {
  const Type& s = *c.args[0];
  if (s.kind == Type::Kind::Opaque) return Typing::success(make_opaque());
  return c.fail(SemanticKind::Type, "expected an opaque type as argument of function '" + c.name() +
                                        "' but got an argument of type " + quoted(s));
}

// lusolve, lltsolve: `<N,M>(s : opaque, b : vector[N](float)) -> vector[M](float)`. The
// right-hand side is only checked for its kind and never overrides explicit bindings.
Typing type_vector_solve(Call& c) {
  Typing s = expect_opaque(c);
  if (!s.ok()) return s;
  const Type& b = *c.args[1];
  if (!numeric_of_order(b, 1))
    return c.fail(SemanticKind::Type, "expected a numeric vector as second argument of function '" +
                                          c.name() + "' but got " + quoted(b));
  c.bind(0, b.dims[0]);
  Typing r = unresolved_check(c);
  if (!r.ok()) return r;
  return Typing::success(make_tensor({c.bindings[1]}, flt()));
}

// lumatsolve, lltmatsolve: `<N,M,K>(s : opaque, B : matrix[N,M](float)) -> matrix[K,M](float)`.
Typing type_matrix_solve(Call& c) {
  Typing s = expect_opaque(c);
  if (!s.ok()) return s;
  const Type& b = *c.args[1];
  if (!numeric_of_order(b, 2))
    return c.fail(SemanticKind::Type, "expected a numeric matrix as second argument of function '" +
                                          c.name() + "' but got " + quoted(b));
  c.bind(0, b.dims[0]);
  c.bind(1, b.dims[1]);
  Typing r = unresolved_check(c);
  if (!r.ok()) return r;
  return Typing::success(make_tensor({c.bindings[2], c.bindings[1]}, flt()));
}

Typing type_free(const Call& c) {
  Typing s = expect_opaque(c);
  return s.ok() ? Typing::success(make_void()) : s;
}

// triangularSolve<N,M>(A : matrix[N,M](float), b : vector[N](float)) -> vector[M](float):
// deduced from the arguments, then checked like any generic call.
Typing type_triangular_solve(Call& c) {
  const Type& a = *c.args[0];
  const Type& b = *c.args[1];
  if (a.order() == 2) {
    c.bind(0, a.dims[0]);
    c.bind(1, a.dims[1]);
  }
  if (b.order() == 1) c.bind(0, b.dims[0]);
  Typing r = unresolved_check(c);
  if (!r.ok()) return r;
  const IndexSet n = c.bindings[0], m = c.bindings[1];
  return fixed_signature(c, {make_tensor({n, m}, flt()), make_tensor({n}, flt())},
                         make_tensor({m}, flt()));
}

// The n of an argument `tensor[n,n](float)` with a fixed n (unblocked), or 0.
int fixed_square(const Type& a) {
  if (a.order() != 2 || !a.block || !a.block->is_scalar() || a.component() != F) return 0;
  const IndexSet& r = a.dims[0];
  if (r.kind != IndexSet::Kind::Fixed || r != a.dims[1]) return 0;
  return r.size;
}

// The logical size of a square float matrix with fixed dimensions whose blocks (at every
// level) are square too, or 0.
int fixed_square_blocked(const Type& a) {
  if (a.is_scalar()) return a.component() == F ? 1 : 0;
  if (!a.is_tensor() || a.order() != 2 || !a.block) return 0;
  const IndexSet& r = a.dims[0];
  if (r.kind != IndexSet::Kind::Fixed || r != a.dims[1]) return 0;
  const int inner = fixed_square_blocked(*a.block);
  return inner ? r.size * inner : 0;
}

Typing wrong_matrix(const Call& c, const char* expected) {
  return c.fail(SemanticKind::Type, "function '" + c.name() + "' takes " + expected +
                                        " but got an argument of type " + quoted(*c.args[0]));
}

// svd(A : tensor[n,n](float)) -> (U : tensor[n,n](float), s : tensor[n](float),
// V : tensor[n,n](float)) and polar(F) -> (R, S), n 2 or 3.
Typing type_rotation_split(const Call& c) {
  const int n = fixed_square(*c.args[0]);
  if (n != 2 && n != 3)
    return wrong_matrix(c,
                        "a 2x2 or 3x3 matrix of float components ('tensor[2,2](float)' or "
                        "'tensor[3,3](float)')");
  if (c.id == Intrinsic::Svd)
    return Typing::success(make_multi({dense({n, n}), dense({n}), dense({n, n})}));
  return Typing::success(make_multi({dense({n, n}), dense({n, n})}));
}

// eig(A : tensor[n,n](float)) -> (w : tensor[n](float), Q : tensor[n,n](float)).
Typing type_eig(const Call& c) {
  const int n = fixed_square(*c.args[0]);
  if (n < 1) return wrong_matrix(c, "a square matrix of float components with fixed dimensions");
  return Typing::success(make_multi({dense({n}), dense({n, n})}));
}

// project_spd(A) and project_spd_abs(A): the argument's own type, square with fixed
// dimensions, blocks (square ones) allowed.
Typing type_project_spd(const Call& c) {
  const Type& a = *c.args[0];
  if (a.order() != 2 || fixed_square_blocked(a) < 1)
    return wrong_matrix(c,
                        "a square matrix of float components with fixed dimensions (square "
                        "blocks allowed)");
  return Typing::success(std::make_shared<const Type>(a));
}

std::vector<const char*> generic_params(Intrinsic id) {
  switch (id) {
    case Intrinsic::Lu:
    case Intrinsic::Chol: return {"N"};
    case Intrinsic::LuSolve:
    case Intrinsic::LltSolve:
    case Intrinsic::TriangularSolve: return {"N", "M"};
    case Intrinsic::LuMatSolve:
    case Intrinsic::LltMatSolve: return {"N", "M", "K"};
    default: return {};
  }
}

size_t param_count(Intrinsic id) {
  switch (id) {
    case Intrinsic::Clock: return 0;
    case Intrinsic::Mod:
    case Intrinsic::Atan2:
    case Intrinsic::Pow:
    case Intrinsic::Max:
    case Intrinsic::Min:
    case Intrinsic::StoreTime:
    case Intrinsic::Cross:
    case Intrinsic::Dot:
    case Intrinsic::CreateComplex:
    case Intrinsic::LuSolve:
    case Intrinsic::LuMatSolve:
    case Intrinsic::LltSolve:
    case Intrinsic::LltMatSolve:
    case Intrinsic::TriangularSolve: return 2;
    default: return 1;
  }
}

TypeRef scalar(ScalarKind k) { return make_scalar(k); }

// The per-intrinsic rule, once counts and argument kinds are known to be sane.
Typing dispatch(Call& c) {
  constexpr ScalarKind I = ScalarKind::Int, C = ScalarKind::Complex;
  switch (c.id) {
    case Intrinsic::Mod: return fixed_signature(c, {scalar(I), scalar(I)}, scalar(I));
    case Intrinsic::Sin:
    case Intrinsic::Cos:
    case Intrinsic::Tan:
    case Intrinsic::Asin:
    case Intrinsic::Acos:
    case Intrinsic::Sqrt:
    case Intrinsic::Cbrt:
    case Intrinsic::Log:
    case Intrinsic::Exp:
    case Intrinsic::Abs: return fixed_signature(c, {flt()}, flt());
    case Intrinsic::Atan2:
    case Intrinsic::Pow:
    case Intrinsic::Max:
    case Intrinsic::Min: return fixed_signature(c, {flt(), flt()}, flt());
    case Intrinsic::Clock: return Typing::success(flt());
    case Intrinsic::StoreTime: return fixed_signature(c, {scalar(I), flt()}, flt());
    case Intrinsic::Det: return fixed_signature(c, {dense({3, 3})}, flt());
    case Intrinsic::Det2: return fixed_signature(c, {dense({2, 2})}, flt());
    case Intrinsic::Det4: return fixed_signature(c, {dense({4, 4})}, flt());
    case Intrinsic::Inv: return fixed_signature(c, {dense({3, 3})}, dense({3, 3}));
    case Intrinsic::Inv2: return fixed_signature(c, {dense({2, 2})}, dense({2, 2}));
    case Intrinsic::Inv4: return fixed_signature(c, {dense({4, 4})}, dense({4, 4}));
    case Intrinsic::Cross: return fixed_signature(c, {dense({3}), dense({3})}, dense({3}));
    case Intrinsic::Norm: return type_norm(c);
    case Intrinsic::Dot: return type_dot(c);
    case Intrinsic::CreateComplex: return fixed_signature(c, {flt(), flt()}, scalar(C));
    case Intrinsic::ComplexGetReal:
    case Intrinsic::ComplexGetImag:
    case Intrinsic::ComplexNorm: return fixed_signature(c, {scalar(C)}, flt());
    case Intrinsic::ComplexConj: return fixed_signature(c, {scalar(C)}, scalar(C));
    case Intrinsic::Lu:
    case Intrinsic::Chol: return type_factorize(c);
    case Intrinsic::LuSolve:
    case Intrinsic::LltSolve: return type_vector_solve(c);
    case Intrinsic::LuMatSolve:
    case Intrinsic::LltMatSolve: return type_matrix_solve(c);
    case Intrinsic::LuFree:
    case Intrinsic::CholFree: return type_free(c);
    case Intrinsic::TriangularSolve: return type_triangular_solve(c);
    case Intrinsic::Svd:
    case Intrinsic::Polar: return type_rotation_split(c);
    case Intrinsic::Eig: return type_eig(c);
    case Intrinsic::ProjectSpd:
    case Intrinsic::ProjectSpdAbs: return type_project_spd(c);
    case Intrinsic::None: break;
  }
  return c.fail(SemanticKind::None, "call of an unknown intrinsic");
}

// Counts and value-ness of the arguments, which no intrinsic relaxes.
Typing check_call_shape(const Call& c, size_t explicit_count) {
  if (explicit_count > c.params.size())
    return c.fail(SemanticKind::Arity, "passed in " + std::to_string(explicit_count) +
                                           " generic arguments but function '" + c.name() +
                                           "' expects " + std::to_string(c.params.size()));
  size_t expected = param_count(c.id);
  if (c.args.size() != expected)
    return c.fail(SemanticKind::Arity, "passed in " + std::to_string(c.args.size()) +
                                           " arguments but function '" + c.name() + "' expects " +
                                           std::to_string(expected));
  for (const Type* a : c.args) {
    if (!a || a->kind == Type::Kind::Void)
      return c.fail(SemanticKind::Type, "must pass a non-void value as argument");
    if (a->kind == Type::Kind::Multi)
      return c.fail(SemanticKind::Type, "cannot pass multiple values as a single argument");
  }
  return Typing::success(flt());
}

}  // namespace

Typing type_intrinsic_call(Intrinsic id, const std::vector<const Type*>& args,
                           const std::vector<IndexSet>& explicit_generics,
                           std::vector<IndexSet>& bindings) {
  std::vector<const char*> params = generic_params(id);
  bindings.assign(params.size(), IndexSet{});
  Call c{id, args, params, std::vector<bool>(params.size(), false), bindings};
  Typing shape = check_call_shape(c, explicit_generics.size());
  if (!shape.ok()) return shape;
  // Explicit generic arguments are bound first, so deduction never overrides them.
  for (size_t i = 0; i < explicit_generics.size(); ++i) c.bind(i, explicit_generics[i]);
  return dispatch(c);
}

}  // namespace simit::frontend
