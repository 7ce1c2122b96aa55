// Visiting the direct subexpressions of an expression node (the interpreter's analyses).
#pragma once

#include "frontend/ast.h"

namespace simit::interp {

// Calls f on every direct subexpression of e, left to right (slices, null indices, are
// skipped).
template <class F>
void for_each_child(const frontend::ast::Expr& e, F&& f) {
  namespace ast = frontend::ast;
  switch (e.kind) {
    case ast::NodeKind::Unary: f(*static_cast<const ast::Unary&>(e).operand); break;
    case ast::NodeKind::Transpose: f(*static_cast<const ast::Transpose&>(e).operand); break;
    case ast::NodeKind::Binary: {
      const auto& b = static_cast<const ast::Binary&>(e);
      f(*b.lhs);
      f(*b.rhs);
      break;
    }
    case ast::NodeKind::Compare:
      for (const auto& o : static_cast<const ast::Compare&>(e).operands) f(*o);
      break;
    case ast::NodeKind::Call:
      for (const auto& a : static_cast<const ast::Call&>(e).args) f(*a);
      break;
    case ast::NodeKind::TensorRead: {
      const auto& r = static_cast<const ast::TensorRead&>(e);
      f(*r.base);
      for (const auto& i : r.indices)
        if (i) f(*i);
      break;
    }
    case ast::NodeKind::FieldRead: f(*static_cast<const ast::FieldRead&>(e).base); break;
    case ast::NodeKind::TupleRead: {
      const auto& t = static_cast<const ast::TupleRead&>(e);
      f(*t.base);
      if (t.index) f(*t.index);
      break;
    }
    case ast::NodeKind::SetRead: {
      const auto& s = static_cast<const ast::SetRead&>(e);
      f(*s.base);
      for (const auto& i : s.first) f(*i);
      for (const auto& i : s.second) f(*i);
      break;
    }
    case ast::NodeKind::Map:
      for (const auto& a : static_cast<const ast::Map&>(e).assembly.args) f(*a);
      break;
    default: break;
  }
}

}  // namespace simit::interp
