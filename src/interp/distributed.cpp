// A distributed run's reductions over sets and ghost refreshes (interp/distribution.h): what
// the interpreter does differently when each MPI rank holds only its part of every set.
#include <cmath>
#include <cstring>
#include <span>
#include <vector>

#include "interp/distribution.h"
#include "interp/frame.h"
#include "interp/interpreter.h"
#include "interp/set_reductions.h"
#include "runtime/blocked_sum.h"
#include "runtime/dense_linalg.h"

namespace simit::interp {

using frontend::IndexSet;
using frontend::SourceSpan;
using frontend::Type;

const runtime::Set* Interpreter::distributed_set(const Type* t) {
  if (!options_.distribution || !is_set_vector(t) || t->dims.empty()) return nullptr;
  const IndexSet& d = t->dims[0];
  if (d.kind == IndexSet::Kind::Fixed || !d.var) return nullptr;
  const Value& v = d.kind == IndexSet::Kind::Generic ? *frame().refs[d.var->slot] : var(*d.var);
  if (v.kind() != Value::Kind::Set || !v.binding()) return nullptr;
  return v.binding()->set;
}

void Interpreter::not_distributed(const SourceSpan& at, const std::string& what) const {
  fail(at, "a distributed run cannot compute " + what + " yet (it runs in one process)");
}

Value Interpreter::distributed_inner_product(const Value& x, const Value& y,
                                             const runtime::Set& set, bool root,
                                             const SourceSpan& at) {
  if (!x.is_tensor() || !y.is_tensor() || x.tensor().kind() != runtime::ComponentKind::Float ||
      y.tensor().kind() != runtime::ComponentKind::Float)
    not_distributed(at, "an inner product over a set of other than float vectors");
  const runtime::Tensor& u = x.tensor();
  const runtime::Tensor& v = y.tensor();
  if (u.size() != v.size() || (set.size() > 0 && u.size() % static_cast<size_t>(set.size()) != 0))
    fail(at, "an inner product of vectors of " + std::to_string(u.size()) + " and " +
                 std::to_string(v.size()) + " components over " + set.describe());
  // A rank may hold no element of a set: it still takes part in the sum.
  const size_t group = runtime::inner_product_group(u.shape());
  if (runtime::inner_product_group(v.shape()) != group || group == 0)
    fail(at, "an inner product of vectors blocked differently");
  // Each element's products summed from +0.0 in order (docs/arithmetic.md, "Sums"); the seam
  // adds the owners' element sums over the whole set in the blocked order ("Distributed runs").
  std::vector<double> sums(u.size() / group);
  const double* a = u.floats();
  const double* b = v.floats();
  for (size_t e = 0; e < sums.size(); ++e) {
    double t = 0.0;
    for (size_t c = e * group; c < (e + 1) * group; ++c) t = t + a[c] * b[c];
    sums[e] = t;
  }
  const double total = options_.distribution->blocked_sum(set, sums);
  return Value::of_float(root ? std::sqrt(total) : total);
}

Value Interpreter::distributed_solve(const frontend::ast::Binary& b, const runtime::SystemMatrix& a,
                                     const Value& rhs) {
  const runtime::Set* set = distributed_set(b.rhs->type.get());
  if (!set || !a.is_float() || rhs.tensor().kind() != runtime::ComponentKind::Float)
    not_distributed(b.span, "a direct solve ('\\') of other than float vectors over a set");
  runtime::Tensor x(runtime::ComponentKind::Float, shape_of(*b.type, b.span));
  if (x.size() != rhs.tensor().size())
    fail(b.span, "the solution has " + std::to_string(x.size()) + " components but '\\' has " +
                     std::to_string(rhs.tensor().size()));
  std::string why;
  if (!options_.distribution->solve(a, *set, {rhs.tensor().floats(), rhs.tensor().size()},
                                    {x.mutable_floats(), x.size()}, why))
    fail(b.span, "a distributed run cannot compute a direct solve ('\\') here: " + why);
  Value out = Value::of_tensor(std::move(x));
  refresh_ghosts(out, b.type.get());
  return out;
}

void Interpreter::refresh_ghosts(Value& v, const Type* t) {
  const runtime::Set* set = distributed_set(t);
  // Every rank takes the same branches here: the refresh is collective.
  if (!set || !v.is_tensor() || !options_.distribution->split(*set)) return;
  runtime::Tensor& x = v.tensor();
  if (x.kind() == runtime::ComponentKind::String) return;
  const size_t bytes = runtime::component_bytes(x.kind()) * x.size();
  const size_t per_element = set->size() > 0 ? bytes / static_cast<size_t>(set->size()) : 0;
  std::byte* data = nullptr;
  switch (x.kind()) {
    case runtime::ComponentKind::Int: data = reinterpret_cast<std::byte*>(x.mutable_ints()); break;
    case runtime::ComponentKind::Bool:
      data = reinterpret_cast<std::byte*>(x.mutable_bools());
      break;
    case runtime::ComponentKind::Complex:
      data = reinterpret_cast<std::byte*>(x.mutable_complexes());
      break;
    default: data = reinterpret_cast<std::byte*>(x.mutable_floats()); break;
  }
  options_.distribution->refresh(*set, std::span<std::byte>(data, bytes), per_element);
}

}  // namespace simit::interp
