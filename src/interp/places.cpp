// Assignment targets and inout places: whole variables, components and blocks.
#include "interp/frame.h"
#include "interp/interpreter.h"

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
      Place p = resolve_place(*r.base, root_override);
      if (p.whole && !p.root->is_tensor()) {
        if (p.root->empty()) fail(r.base->span, "assignment into a variable that has no value");
        unsupported(r.span, "writes into non-tensor values");
      }
      Shape s = p.whole ? p.root->tensor().shape() : p.shape;
      size_t offset = p.whole ? 0 : p.offset;
      if (s.is_scalar() || static_cast<int>(r.indices.size()) != s.order())
        fail(r.span, "wrong number of indices for a tensor of shape " + s.str());
      size_t outer = 0;
      for (size_t k = 0; k < r.indices.size(); ++k) {
        if (!r.indices[k]) fail(r.span, "a slice cannot be assigned");
        int d = s.dim(static_cast<int>(k));
        outer = outer * d + index_value(*r.indices[k], d);
      }
      Shape block = s.block();
      return Place{p.root, false, offset + outer * block.size(), block};
    }
    case ast::NodeKind::FieldRead:
    case ast::NodeKind::TupleRead: unsupported(target.span, "element fields and set fields");
    default: break;
  }
  fail(target.span, "expression is not assignable");
}

Value Interpreter::read_place(const Place& p) const {
  if (p.whole) return *p.root;
  if (p.shape.is_scalar()) return Value::component(p.root->tensor(), p.offset);
  return Value::of_tensor(p.root->tensor().range(p.offset, p.shape));
}

void Interpreter::write_place(const Place& p, Value value, const SourceSpan& at) {
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
