// Literal values, type matching and result comparison for the interpreter's executors.
#include "value_match.h"

#include <algorithm>
#include <cmath>

#include "interp/set_binding.h"
#include "runtime/dense_linalg.h"

namespace simit::tools {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::ScalarKind;
using frontend::Type;
using interp::Value;
using runtime::ComponentKind;
using runtime::Shape;
using runtime::Tensor;

namespace {

bool dim_matches(const IndexSet& wanted, const IndexSet& actual, GenericSizes& sizes) {
  if (actual.kind != IndexSet::Kind::Fixed) return wanted == actual;
  switch (wanted.kind) {
    case IndexSet::Kind::Fixed: return wanted.size == actual.size;
    case IndexSet::Kind::Generic: {
      auto [it, fresh] = sizes.emplace(wanted.var, actual.size);
      return fresh || it->second == actual.size;
    }
    case IndexSet::Kind::Set: return false;
  }
  return false;
}

bool float_close(double a, double b, std::optional<double> tol) {
  if (a == b) return true;
  if (tol) return std::fabs(a - b) <= *tol;
  return std::fabs(a - b) / std::max(std::fabs(a), std::fabs(b)) <= 1e-3;
}

bool component_close(const Tensor& a, const Tensor& b, size_t i, std::optional<double> tol) {
  switch (a.kind()) {
    case ComponentKind::Int: return a.ints()[i] == b.ints()[i];
    case ComponentKind::Bool: return a.bools()[i] == b.bools()[i];
    case ComponentKind::String: return a.strings()[i] == b.strings()[i];
    case ComponentKind::Float: return float_close(a.floats()[i], b.floats()[i], tol);
    case ComponentKind::Complex:
      return float_close(a.complexes()[i].real(), b.complexes()[i].real(), tol) &&
             float_close(a.complexes()[i].imag(), b.complexes()[i].imag(), tol);
  }
  return false;
}

}  // namespace

bool type_matches(const Type& wanted, const Type& actual, GenericSizes& sizes,
                  bool ignore_orientation) {
  if (wanted.kind != actual.kind) return false;
  if (wanted.kind == Type::Kind::Scalar) return wanted.scalar == actual.scalar;
  if (wanted.kind != Type::Kind::Tensor) return frontend::types_equal(wanted, actual);
  if (wanted.dims.size() != actual.dims.size()) return false;
  if (wanted.dims.size() == 1 && !ignore_orientation && wanted.row != actual.row) return false;
  for (size_t i = 0; i < wanted.dims.size(); ++i)
    if (!dim_matches(wanted.dims[i], actual.dims[i], sizes)) return false;
  if (!wanted.block || !actual.block) return wanted.block == actual.block;
  return type_matches(*wanted.block, *actual.block, sizes, ignore_orientation);
}

frontend::TypeRef literal_type(const Literal& lit) {
  frontend::TypeRef scalar = frontend::make_scalar(lit.kind);
  if (lit.is_scalar()) return scalar;
  std::vector<IndexSet> dims;
  for (int d : lit.shape) dims.push_back(IndexSet::fixed(d));
  return frontend::make_tensor(std::move(dims), scalar, lit.shape.size() == 1 && !lit.column);
}

Value literal_value(const Literal& lit) {
  const ComponentKind kind = interp::component_of(lit.kind);
  Tensor t(kind, lit.is_scalar() ? Shape() : Shape::of(lit.shape));
  for (size_t i = 0; i < lit.size(); ++i) {
    switch (kind) {
      case ComponentKind::Int: t.mutable_ints()[i] = static_cast<int32_t>(lit.ints[i]); break;
      case ComponentKind::Bool: t.mutable_bools()[i] = lit.ints[i] != 0; break;
      case ComponentKind::Float: t.mutable_floats()[i] = lit.floats[i]; break;
      case ComponentKind::Complex: t.mutable_complexes()[i] = lit.complexes[i]; break;
      case ComponentKind::String: t.mutable_strings()[i] = lit.string_value; break;
    }
  }
  return lit.is_scalar() ? Value::component(t, 0) : Value::of_tensor(std::move(t));
}

bool values_match(const Value& actual, const Value& expected, std::optional<double> abs_tolerance) {
  if (actual.empty() || expected.empty()) return false;
  if (actual.component_kind() != expected.component_kind()) return false;
  // Orientation is not part of a value; blocked tensors compare in their unblocked form.
  Tensor a = actual.to_tensor(), b = expected.to_tensor();
  if (a.shape().is_blocked() && a.shape().uniform()) a = runtime::unblock(a);
  if (b.shape().is_blocked() && b.shape().uniform()) b = runtime::unblock(b);
  if (a.shape() != b.shape()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (!component_close(a, b, i, abs_tolerance)) return false;
  return true;
}

}  // namespace simit::tools
