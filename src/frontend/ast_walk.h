// The one walk over the tree's children: the direct subexpressions of an expression, and the
// root expressions and nested blocks of a statement. Every analysis builds on these two.
#pragma once

#include "frontend/ast.h"

namespace simit::frontend::ast {

// Calls f on every direct subexpression of e, left to right (slices, null indices, are
// skipped). For a map, its arguments.
template <class F>
void for_each_child(const Expr& e, F&& f) {
  auto visit = [&](const ExprPtr& c) {
    if (c) f(*c);
  };
  switch (e.kind) {
    case NodeKind::Unary: visit(static_cast<const Unary&>(e).operand); break;
    case NodeKind::Transpose: visit(static_cast<const Transpose&>(e).operand); break;
    case NodeKind::Binary:
      visit(static_cast<const Binary&>(e).lhs);
      visit(static_cast<const Binary&>(e).rhs);
      break;
    case NodeKind::Compare:
      for (const auto& o : static_cast<const Compare&>(e).operands) visit(o);
      break;
    case NodeKind::Call:
      for (const auto& a : static_cast<const Call&>(e).args) visit(a);
      break;
    case NodeKind::TensorRead: {
      const auto& r = static_cast<const TensorRead&>(e);
      visit(r.base);
      for (const auto& i : r.indices) visit(i);
      break;
    }
    case NodeKind::FieldRead: visit(static_cast<const FieldRead&>(e).base); break;
    case NodeKind::TupleRead:
      visit(static_cast<const TupleRead&>(e).base);
      visit(static_cast<const TupleRead&>(e).index);
      break;
    case NodeKind::SetRead: {
      const auto& s = static_cast<const SetRead&>(e);
      visit(s.base);
      for (const auto& i : s.first) visit(i);
      for (const auto& i : s.second) visit(i);
      break;
    }
    case NodeKind::Map:
      for (const auto& a : static_cast<const Map&>(e).assembly.args) visit(a);
      break;
    default: break;
  }
}

// Calls root(expr) on each root expression of statement s in execution order (an
// assignment's value before its targets) and block(b) on each nested block.
template <class R, class B>
void for_each_stmt_part(const Stmt& s, R&& root, B&& block) {
  switch (s.kind) {
    case NodeKind::VarDecl:
      if (const auto& init = static_cast<const VarDecl&>(s).init) root(*init);
      break;
    case NodeKind::Assign: {
      const auto& a = static_cast<const Assign&>(s);
      root(*a.value);
      for (const auto& t : a.targets) root(*t);
      break;
    }
    case NodeKind::ExprStmt: root(*static_cast<const ExprStmt&>(s).expr); break;
    case NodeKind::If: {
      const auto& i = static_cast<const If&>(s);
      for (size_t k = 0; k < i.conditions.size(); ++k) {
        root(*i.conditions[k]);
        block(i.branches[k]);
      }
      block(i.else_branch);
      break;
    }
    case NodeKind::While: {
      const auto& w = static_cast<const While&>(s);
      root(*w.condition);
      block(w.body);
      break;
    }
    case NodeKind::DoWhile: {
      const auto& d = static_cast<const DoWhile&>(s);
      block(d.body);
      root(*d.condition);
      break;
    }
    case NodeKind::ForRange: {
      const auto& f = static_cast<const ForRange&>(s);
      root(*f.lo);
      root(*f.hi);
      block(f.body);
      break;
    }
    case NodeKind::ForSet: block(static_cast<const ForSet&>(s).body); break;
    case NodeKind::Print:
      for (const auto& a : static_cast<const Print&>(s).args) root(*a);
      break;
    case NodeKind::Apply:
      for (const auto& a : static_cast<const Apply&>(s).assembly.args) root(*a);
      break;
    default: break;
  }
}

}  // namespace simit::frontend::ast
