// Declarations and type builders shared by the type and operator-typing unit tests.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "frontend/ast.h"
#include "frontend/types.h"

namespace simit::frontend::testing {

// A small world: element types Node and Bar, vertex sets nodes/points of Node, edge
// set springs of Bar over nodes, and a generic parameter N.
class TypeWorld {
 public:
  TypeWorld() {
    node.name = "Node";
    bar.name = "Bar";
    init_set(nodes, "nodes", vertex_set(&node));
    init_set(points, "points", vertex_set(&node));
    init_set(springs, "springs", edge_set(&bar, {set(nodes), set(nodes)}));
    N.name = "N";
    N.kind = ast::Variable::Kind::Generic;
    M.name = "M";
    M.kind = ast::Variable::Kind::Generic;
  }

  ast::ElementDecl node{SourceSpan{}};
  ast::ElementDecl bar{SourceSpan{}};
  ast::Variable nodes, points, springs, N, M;

  static IndexSet fixed(int n) { return IndexSet::fixed(n); }
  static IndexSet set(const ast::Variable& v) { return IndexSet::set(&v); }
  static IndexSet generic(const ast::Variable& v) { return IndexSet::generic(&v); }

  static TypeRef i() { return make_scalar(ScalarKind::Int); }
  static TypeRef f() { return make_scalar(ScalarKind::Float); }
  static TypeRef b() { return make_scalar(ScalarKind::Bool); }
  static TypeRef c() { return make_scalar(ScalarKind::Complex); }
  static TypeRef s() { return make_scalar(ScalarKind::String); }

  // Column vector, row vector and matrix over `dims` with block `blk`.
  static TypeRef col(IndexSet d, TypeRef blk = f()) { return make_tensor({d}, blk, false); }
  static TypeRef row(IndexSet d, TypeRef blk = f()) { return make_tensor({d}, blk, true); }
  static TypeRef mat(IndexSet a, IndexSet b, TypeRef blk = f()) { return make_tensor({a, b}, blk); }
  static TypeRef col(int n, TypeRef blk = f()) { return col(fixed(n), blk); }
  static TypeRef row(int n, TypeRef blk = f()) { return row(fixed(n), blk); }
  static TypeRef mat(int a, int b, TypeRef blk = f()) { return mat(fixed(a), fixed(b), blk); }

  static TypeRef vertex_set(const ast::ElementDecl* e) { return edge_set(e, {}); }
  static TypeRef edge_set(const ast::ElementDecl* e, std::vector<IndexSet> endpoints) {
    auto t = std::make_shared<Type>();
    t->kind = Type::Kind::Set;
    t->element = e;
    t->endpoints = std::move(endpoints);
    return t;
  }
  static TypeRef grid(const ast::ElementDecl* e, int dims, IndexSet point_set) {
    auto t = std::make_shared<Type>();
    t->kind = Type::Kind::Set;
    t->element = e;
    t->grid_dims = dims;
    t->endpoints = {point_set};
    return t;
  }
  static TypeRef element(const ast::ElementDecl* e) {
    auto t = std::make_shared<Type>();
    t->kind = Type::Kind::Element;
    t->element = e;
    return t;
  }
  static TypeRef element_of(const ast::ElementDecl* e, IndexSet source) {
    auto t = std::make_shared<Type>();
    t->kind = Type::Kind::Element;
    t->element = e;
    t->source = source;
    t->has_source = true;
    return t;
  }
  static TypeRef tuple(std::vector<TypeRef> members, std::vector<std::string> names = {}) {
    auto t = std::make_shared<Type>();
    t->kind = Type::Kind::Tuple;
    t->members = std::move(members);
    t->names = std::move(names);
    return t;
  }

 private:
  static void init_set(ast::Variable& v, const char* name, TypeRef type) {
    v.name = name;
    v.kind = ast::Variable::Kind::Extern;
    v.type = std::move(type);
  }
};

}  // namespace simit::frontend::testing
