// Assignment targets and inout places: whole variables, components and blocks.
#include "interp/frame.h"
#include "interp/interpreter.h"
#include "interp/map_context.h"
#include "interp/system_values.h"
#include "runtime/fault.h"
#include "runtime/sum_rounding.h"

namespace simit::interp {

namespace ast = frontend::ast;
using frontend::SourceSpan;

Place Interpreter::resolve_place(const ast::Expr& target, Value* root_override) {
  switch (target.kind) {
    case ast::NodeKind::VarRef: {
      Place p;
      p.root = root_override ? root_override : &var(*static_cast<const ast::VarRef&>(target).var);
      return p;
    }
    case ast::NodeKind::TensorRead: {
      const auto& r = static_cast<const ast::TensorRead&>(target);
      const auto* fr = r.base->as<ast::FieldRead>();
      if (fr && fr->of_set && r.indices.size() == 1 && r.indices[0]) {
        // `S.f(e) = b`: the field of one element.
        Value set = eval(*fr->base), e = eval(*r.indices[0]);
        if (e.kind() != Value::Kind::Element) fail(r.span, "set fields are indexed by elements");
        return field_element_place(*set.binding(), fr->field_index, e.index(), r.span);
      }
      Place p = resolve_place(*r.base, root_override);
      if (p.field_set) p.whole = false;  // a part of the field's array: offset and shape
      if (p.whole && p.root->kind() == Value::Kind::Matrix) {
        if (is_map_result(p.root)) return matrix_place(r, *p.root);
        fail(r.span, "a system matrix can only be written by assembly");
      }
      const bool map_result = p.whole && is_map_result(p.root);
      if (map_result) p.accumulate = map_->reduce;
      if (p.whole && !p.root->is_tensor()) {
        if (p.root->empty()) fail(r.base->span, "assignment into a variable that has no value");
        unsupported(r.span, "writes into non-tensor values");
      }
      const Shape& s = p.whole ? p.root->tensor().shape() : p.shape;
      size_t offset = p.whole ? 0 : p.offset;
      if (s.is_scalar() || static_cast<int>(r.indices.size()) != s.order())
        fail(r.span, "wrong number of indices for a tensor of shape " + s.str());
      size_t outer = 0;
      for (size_t k = 0; k < r.indices.size(); ++k) {
        if (!r.indices[k]) fail(r.span, "a slice cannot be assigned");
        int d = s.dim(static_cast<int>(k));
        Value scratch;
        const Value& index = operand(*r.indices[k], scratch);
        // A write into a global vector result must name the visited element or an endpoint.
        if (map_result && index.kind() == Value::Kind::Element) check_vector_write(r, index);
        outer = outer * d + checked_index(index, *r.indices[k], d);
      }
      Shape block = s.block();
      p.whole = false;
      p.offset = offset + outer * block.size();
      p.shape = block;
      return p;
    }
    case ast::NodeKind::FieldRead: return field_place(static_cast<const ast::FieldRead&>(target));
    default: break;
  }
  fail(target.span, "expression is not assignable");
}

Value Interpreter::read_place(const Place& p) const {
  if (p.field_set) return read_field(p);
  if (p.whole) return *p.root;
  if (p.shape.is_scalar()) return Value::component(p.root->tensor(), p.offset);
  return Value::of_tensor(p.root->tensor().range(p.offset, p.shape));
}

namespace {

// `reduce +` writes add (§8.5.4); the target is a tensor or a system matrix's values.
// dst += v over count components; under float32 each addition rounded to binary32 (an
// assembled block adds its contributions in binary32 steps: docs/arithmetic.md).
template <class T>
void add_into(T* dst, const Value& v, size_t count, bool float32) {
  runtime::with_sums(float32, [&]<class R>(R) {
    if (v.is_tensor()) {
      const Tensor& t = v.tensor();
      if (t.size() != count)
        throw runtime::Fault("cannot add a value of shape " + t.shape().str() + " into a part of " +
                             std::to_string(count) + " components");
      if constexpr (std::is_same_v<T, double>) {
        const double* s = t.floats();
        for (size_t i = 0; i < count; ++i) dst[i] = R::r(dst[i] + s[i]);
      } else if constexpr (std::is_same_v<T, int32_t>) {
        const int32_t* s = t.ints();
        for (size_t i = 0; i < count; ++i) dst[i] += s[i];
      } else {
        const Complex* s = t.complexes();
        for (size_t i = 0; i < count; ++i) dst[i] = R::r(dst[i] + s[i]);
      }
      return;
    }
    for (size_t i = 0; i < count; ++i) {
      if constexpr (std::is_same_v<T, double>)
        dst[i] = R::r(dst[i] + v.as_float());
      else if constexpr (std::is_same_v<T, int32_t>)
        dst[i] += v.as_int();
      else
        dst[i] = R::r(dst[i] + v.as_complex());
    }
  });
}

}  // namespace

void Interpreter::write_place(const Place& p, Value value, const SourceSpan& at) {
  try {
    if (p.field_set)
      write_field(p, std::move(value), at);
    else
      write_place_raw(p, std::move(value), at);
  } catch (const runtime::Fault& f) {
    fail(at, f.what());
  }
}

void Interpreter::write_place_raw(const Place& p, Value value, const SourceSpan& at) {
  // A block of a system matrix (assembly); a whole matrix variable is replaced below.
  if (!p.whole && p.root->kind() == Value::Kind::Matrix)
    return write_matrix_part(*p.root->matrix(), p.offset, p.shape.size(), value, p.accumulate,
                             options_.float32);
  if (p.accumulate && !p.whole) {
    Tensor& t = p.root->tensor();
    const size_t n = p.shape.size();
    switch (t.kind()) {
      case ComponentKind::Float:
        return add_into(t.mutable_floats() + p.offset, value, n, options_.float32);
      case ComponentKind::Int: return add_into(t.mutable_ints() + p.offset, value, n, false);
      case ComponentKind::Complex:
        return add_into(t.mutable_complexes() + p.offset, value, n, options_.float32);
      case ComponentKind::Bool:
        throw runtime::Fault("'reduce +' cannot assemble a vector of bool components");
      default: break;
    }
  }
  if (p.whole) {
    Value& dst = *p.root;
    if (value.is_scalar() && dst.is_tensor()) {  // broadcast (§7.1)
      value.fill_into(dst.tensor(), 0, dst.tensor().size());
      return;
    }
    dst = std::move(value);
    return;
  }
  Tensor& t = p.root->tensor();
  if (value.is_scalar()) {
    value.fill_into(t, p.offset, p.shape.size());
    return;
  }
  if (!value.is_tensor() || value.tensor().size() != p.shape.size())
    fail(at, "cannot store a value of shape " + value.shape().str() + " into a part of shape " +
                 p.shape.str());
  t.write_range(p.offset, value.tensor());
}

}  // namespace simit::interp
