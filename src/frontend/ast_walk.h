// The walks over the tree's children, generated from the node lists of frontend/ast.h: the
// direct subexpressions of an expression, and the root expressions and nested blocks of a
// statement. Every analysis builds on these two.
#pragma once

#include "frontend/ast.h"

namespace simit::frontend::ast {

namespace walk_detail {

template <class F>
void each_expr(const ExprPtr& e, F& f) {
  if (e) f(*e);  // a null index is a slice `:`, an absent initialiser
}
template <class F>
void each_expr(const std::vector<ExprPtr>& list, F& f) {
  for (const auto& e : list) each_expr(e, f);
}
template <class F>
void each_block(const Block& b, F& f) {
  f(b);
}
template <class F>
void each_block(const std::vector<Block>& list, F& f) {
  for (const auto& b : list) f(b);
}

}  // namespace walk_detail

// Calls f on every direct subexpression of e, left to right (slices, null indices, are
// skipped). For a map, its arguments.
template <class F>
void for_each_child(const Expr& e, F&& f) {
  auto visit = [&](const auto&... members) { (walk_detail::each_expr(members, f), ...); };
  switch (e.kind) {
#define SIMIT_WALK_CHILDREN(Node, ...)                            \
  case NodeKind::Node: {                                          \
    [[maybe_unused]] const auto& n = static_cast<const Node&>(e); \
    visit(__VA_ARGS__);                                           \
    break;                                                        \
  }
    SIMIT_EXPR_CHILDREN(SIMIT_WALK_CHILDREN)
#undef SIMIT_WALK_CHILDREN
    default: break;
  }
}

// Calls root(expr) on each root expression of statement s (an assignment's value before
// its targets, an if's conditions before its branches) and block(b) on each nested block.
template <class R, class B>
void for_each_stmt_part(const Stmt& s, R&& root, B&& block) {
  [[maybe_unused]] auto roots = [&](const auto&... members) {
    (walk_detail::each_expr(members, root), ...);
  };
  [[maybe_unused]] auto blocks = [&](const auto&... members) {
    (walk_detail::each_block(members, block), ...);
  };
  switch (s.kind) {
#define SIMIT_WALK_PARTS(Node, root_members, block_members)       \
  case NodeKind::Node: {                                          \
    [[maybe_unused]] const auto& n = static_cast<const Node&>(s); \
    roots root_members;                                           \
    blocks block_members;                                         \
    break;                                                        \
  }
    SIMIT_STMT_PARTS(SIMIT_WALK_PARTS)
#undef SIMIT_WALK_PARTS
    default: break;
  }
}

}  // namespace simit::frontend::ast
