// Value text for the step debugger.
#include "debug_values.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "interp/printing.h"
#include "interp/set_binding.h"
#include "runtime/set.h"

namespace simit::repl {

namespace {

// Tensors with more components than this are summarised rather than listed.
constexpr size_t kListedComponents = 64;

std::string element_text(const runtime::Set& set, int index) {
  if (set.name().empty()) return "element " + std::to_string(index);
  return set.name() + "[" + std::to_string(index) + "]";
}

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

// `<vector[verts](vector[3](float)), 81 components: min -1, max 2, 3 NaN>`.
std::string tensor_summary(const runtime::Tensor& t, const frontend::Type* type) {
  std::string what = type && type->kind == frontend::Type::Kind::Tensor
                         ? frontend::to_string(*type)
                         : t.shape().str() + " tensor";
  std::string out = "<" + what + ", " + std::to_string(t.size()) + " components";
  if (t.kind() != runtime::ComponentKind::Float) return out + ">";
  const double* x = t.floats();
  double lo = INFINITY, hi = -INFINITY;
  size_t nan = 0, inf = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    if (std::isnan(x[i]))
      ++nan;
    else if (std::isinf(x[i]))
      ++inf;
    else
      lo = std::min(lo, x[i]), hi = std::max(hi, x[i]);
  }
  if (lo <= hi) out += ": min " + number(lo) + ", max " + number(hi);
  if (nan) out += ", " + std::to_string(nan) + " NaN";
  if (inf) out += ", " + std::to_string(inf) + " infinite";
  return out + ">";
}

bool finite(const double* x, size_t n) {
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(x[i])) return false;
  return true;
}

}  // namespace

std::string value_text(const interp::Value& v, const frontend::Type* type) {
  using K = interp::Value::Kind;
  switch (v.kind()) {
    case K::Empty: return "<no value>";
    case K::Tensor: {
      if (v.tensor().size() > kListedComponents) return tensor_summary(v.tensor(), type);
      bool column = !(type && type->kind == frontend::Type::Kind::Tensor && type->row);
      return interp::literal_text(v, column);
    }
    case K::Element:
      return v.binding() && v.binding()->set ? element_text(*v.binding()->set, v.index())
                                             : "element " + std::to_string(v.index());
    case K::Tuple: {
      if (!v.binding() || !v.binding()->set) return "<endpoints>";
      const runtime::Set& edges = *v.binding()->set;
      std::string out = "(";
      for (int k = 0; k < edges.arity(); ++k)
        out += (k ? ", " : "") + element_text(edges.endpoint_set(k), edges.endpoint(v.index(), k));
      return out + ")";
    }
    case K::Set: {
      const runtime::Set* s = v.binding() ? v.binding()->set : nullptr;
      if (!s) return "<set>";
      return "<set " + s->name() + " of " + std::to_string(s->size()) + " elements>";
    }
    case K::Matrix: {
      const runtime::SystemMatrix& m = *v.matrix();
      return "<system matrix of " + std::to_string(m.rows()) + "x" + std::to_string(m.cols()) +
             " blocks " + std::to_string(m.block_rows()) + "x" + std::to_string(m.block_cols()) +
             ", " + std::to_string(m.pattern().nnz()) + " stored>";
    }
    case K::Opaque: return "<solver factorisation>";
    default: return interp::literal_text(v, false);
  }
}

bool all_finite(const interp::Value& v) {
  using K = interp::Value::Kind;
  switch (v.kind()) {
    case K::Float: return std::isfinite(v.as_float());
    case K::Complex:
      return std::isfinite(v.as_complex().real()) && std::isfinite(v.as_complex().imag());
    case K::Tensor: {
      const runtime::Tensor& t = v.tensor();
      if (t.kind() == runtime::ComponentKind::Float) return finite(t.floats(), t.size());
      if (t.kind() == runtime::ComponentKind::Complex)
        return finite(reinterpret_cast<const double*>(t.complexes()), 2 * t.size());
      return true;
    }
    case K::Matrix:
      return !v.matrix()->is_float() || finite(v.matrix()->values(), v.matrix()->value_count());
    default: return true;
  }
}

}  // namespace simit::repl
