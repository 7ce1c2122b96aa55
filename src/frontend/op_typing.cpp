// Typing of unary, binary, transpose and comparison operators (LANGUAGE.md §6.4-6.9).
#include "frontend/op_typing.h"

namespace simit::frontend {

namespace {

using Op = ast::Binary::Op;

std::string quoted(const Type& t) { return "'" + to_string(t) + "'"; }

TypeRef copy_of(const Type& t) { return std::make_shared<const Type>(t); }

const char* compare_spelling(ast::Compare::Op op) {
  switch (op) {
    case ast::Compare::Op::Eq: return "==";
    case ast::Compare::Op::Ne: return "!=";
    case ast::Compare::Op::Lt: return "<";
    case ast::Compare::Op::Gt: return ">";
    case ast::Compare::Op::Le: return "<=";
    case ast::Compare::Op::Ge: return ">=";
  }
  return "?";
}

bool is_numeric(ScalarKind k) {
  return k == ScalarKind::Int || k == ScalarKind::Float || k == ScalarKind::Complex;
}

bool numeric_tensor(const Type& t) { return t.is_tensor() && is_numeric(t.component()); }

bool is_bool_scalar(const Type& t) { return t.is_scalar() && t.scalar == ScalarKind::Bool; }

// A system matrix: an order-2 tensor over sets. Generic dimensions are left to the
// instantiated check, where they are bound to sets or sizes.
bool is_system_matrix(const Type& t) {
  if (t.order() != 2) return false;
  for (const IndexSet& d : t.dims)
    if (d.kind == IndexSet::Kind::Set) return true;
  return false;
}

// Tensor equality that ignores the orientation of vectors at every blocking level.
bool equal_ignoring_orientation(const Type& a, const Type& b) {
  if (a.kind != b.kind) return false;
  if (a.kind != Type::Kind::Tensor) return types_equal(a, b);
  if (a.dims != b.dims || !a.block || !b.block) return false;
  return equal_ignoring_orientation(*a.block, *b.block);
}

std::string component_phrase(ScalarKind k) {
  switch (k) {
    case ScalarKind::Int: return "an integer";
    case ScalarKind::Float: return "a floating-point";
    case ScalarKind::Complex: return "a complex";
    case ScalarKind::Bool: return "a boolean";
    case ScalarKind::String: return "a string";
  }
  return "a";
}

std::string operand_error(const char* side, const char* what, const Type& t) {
  return std::string("expected ") + side + " operand of " + what +
         " to be a numeric tensor but got a value of type " + quoted(t);
}

// Checks that both operands are numeric with one component type.
Typing check_numeric_pair(const char* what, const Type& l, const Type& r) {
  if (!numeric_tensor(l))
    return Typing::failure(SemanticKind::Type, operand_error("left", what, l));
  if (!numeric_tensor(r))
    return Typing::failure(SemanticKind::Type, operand_error("right", what, r));
  if (l.component() != r.component())
    return Typing::failure(SemanticKind::Type,
                           "cannot combine " + component_phrase(l.component()) + " tensor with " +
                               component_phrase(r.component()) + " tensor in " + what);
  return Typing::success(make_scalar(l.component()));
}

// ---------------------------------------------------------------------------
// Element-wise + - .* ./

Typing elementwise_mismatch(const Type& l, const Type& r) {
  std::string msg = "cannot perform element-wise operation on tensors of type " + quoted(l) +
                    " and type " + quoted(r);
  // Same shape read either way round: the only difference is orientation.
  bool orientation_only = l.order() == r.order() && equal_ignoring_orientation(l, r);
  return Typing::failure(orientation_only ? SemanticKind::Type : SemanticKind::Dimension, msg);
}

Typing type_elementwise(Op op, const Type& l, const Type& r) {
  if (op == Op::Add && l.is_scalar() && r.is_scalar() && l.scalar == ScalarKind::String &&
      r.scalar == ScalarKind::String)
    return Typing::success(make_scalar(ScalarKind::String));
  Typing pair = check_numeric_pair("element-wise operation", l, r);
  if (!pair.ok()) return pair;
  bool additive = op == Op::Add || op == Op::Sub;
  if (l.is_scalar() || r.is_scalar()) {
    const Type& tensor = l.is_scalar() ? r : l;
    // A sparse matrix has no storage for the components a broadcast would fill.
    if (additive && is_system_matrix(tensor))
      return Typing::failure(
          SemanticKind::Type,
          "cannot add a scalar to or subtract it from the system matrix " + quoted(tensor));
    return Typing::success(copy_of(tensor));
  }
  if (!types_equal(l, r)) return elementwise_mismatch(l, r);
  return Typing::success(copy_of(l));
}

// ---------------------------------------------------------------------------
// Products `*`, level by level through the blocks

struct Product {
  TypeRef type;  // null on failure
  SemanticKind kind = SemanticKind::None;
  std::string error;
};

Product product_failure(SemanticKind k, std::string msg) { return {nullptr, k, std::move(msg)}; }

// One blocking level of a product. Blocks of vectors are stored as columns; in a product
// they take the role (row or column) of the vector they belong to. `lt`/`rt` are the
// whole operands, for messages; `top` marks the outermost level, the only one whose
// result vectors may be rows.
struct Level {
  const Type& l;
  bool lrow;
  const Type& r;
  bool rrow;
  bool top;
  const Type& lt;
  const Type& rt;
};

Product multiply_level(const Level& x);

Product dimension_failure(const Level& x) {
  auto noun = [](const Type& t) { return t.order() == 2 ? "a matrix" : "a vector"; };
  return product_failure(SemanticKind::Dimension, std::string("cannot multiply ") + noun(x.lt) +
                                                      " of type " + quoted(x.lt) + " by " +
                                                      noun(x.rt) + " of type " + quoted(x.rt));
}

// The product of the blocks of `x.l` (in the role of a row when `lrow`) and `x.r`.
Product multiply_blocks(const Level& x, bool lrow, bool rrow) {
  const TypeRef& lb = x.l.block;
  const TypeRef& rb = x.r.block;
  if (!lb || !rb) return dimension_failure(x);
  if (lb->is_scalar() && rb->is_scalar()) return {make_scalar(lb->scalar), SemanticKind::None, {}};
  if (lb->is_scalar() || rb->is_scalar()) return dimension_failure(x);
  return multiply_level({*lb, lrow, *rb, rrow, false, x.lt, x.rt});
}

Product make_product(std::vector<IndexSet> dims, const Product& block, bool row) {
  if (!block.type) return block;
  return {make_tensor(std::move(dims), block.type, row), SemanticKind::None, {}};
}

Product vector_times_vector(const Level& x) {
  if (x.lrow == x.rrow)
    return product_failure(SemanticKind::Type, x.lrow ? "cannot multiply two row vectors"
                                                      : "cannot multiply two column vectors");
  if (x.lrow) {  // inner product
    if (x.l.dims != x.r.dims) return dimension_failure(x);
    Product b = multiply_blocks(x, true, false);
    return b.type && !b.type->is_scalar() ? dimension_failure(x) : b;
  }
  // An outer product of global vectors would be a dense S x S matrix.
  if (x.top && (x.l.is_global() || x.r.is_global()))
    return product_failure(SemanticKind::Type,
                           "cannot compute the outer product of global vectors " + quoted(x.lt) +
                               " and " + quoted(x.rt));
  return make_product({x.l.dims[0], x.r.dims[0]}, multiply_blocks(x, false, true), false);
}

Product matrix_times_vector(const Level& x) {
  if (x.rrow)
    return product_failure(SemanticKind::Type, "cannot multiply a matrix by a row vector");
  if (x.l.dims[1] != x.r.dims[0]) return dimension_failure(x);
  return make_product({x.l.dims[0]}, multiply_blocks(x, false, false), false);
}

Product vector_times_matrix(const Level& x) {
  if (!x.lrow)
    return product_failure(SemanticKind::Type, "cannot multiply a column vector by a matrix");
  if (x.l.dims[0] != x.r.dims[0]) return dimension_failure(x);
  return make_product({x.r.dims[1]}, multiply_blocks(x, true, false), x.top);
}

Product multiply_level(const Level& x) {
  int lo = x.l.order(), ro = x.r.order();
  if (lo == 1 && ro == 1) return vector_times_vector(x);
  if (lo == 2 && ro == 1) return matrix_times_vector(x);
  if (lo == 1 && ro == 2) return vector_times_matrix(x);
  if (lo != 2 || ro != 2 || x.l.dims[1] != x.r.dims[0]) return dimension_failure(x);
  return make_product({x.l.dims[0], x.r.dims[1]}, multiply_blocks(x, false, false), false);
}

Typing type_multiply(const Type& l, const Type& r) {
  Typing pair = check_numeric_pair("multiplication operation", l, r);
  if (!pair.ok()) return pair;
  if (l.is_scalar()) return Typing::success(copy_of(r));
  if (r.is_scalar()) return Typing::success(copy_of(l));
  if (l.order() >= 3 || r.order() >= 3)
    return Typing::failure(SemanticKind::Type,
                           "cannot multiply tensors of order 3 or greater using *");
  Product p = multiply_level({l, l.row, r, r.row, true, l, r});
  if (!p.type) return Typing::failure(p.kind, p.error);
  return Typing::success(p.type);
}

// ---------------------------------------------------------------------------
// Division `/` and solve `\`

Typing type_divide(const Type& l, const Type& r) {
  Typing pair = check_numeric_pair("division", l, r);
  if (!pair.ok()) return pair;
  if (l.is_scalar()) return Typing::success(copy_of(r));
  if (r.is_scalar()) return Typing::success(copy_of(l));
  return Typing::failure(SemanticKind::Type, "division of a non-scalar tensor of type " +
                                                 quoted(l) + " by a non-scalar tensor of type " +
                                                 quoted(r) + " is not supported; use ./");
}

// The block of the solution of `A x = b` for blocks `a` of A and `b` of b, or null.
TypeRef solve_block(const Type& a, const Type& b) {
  if (a.is_scalar() && b.is_scalar()) return make_scalar(a.scalar);
  if (a.order() != 2 || b.order() != 1 || a.dims[0] != b.dims[0] || !a.block || !b.block)
    return nullptr;
  TypeRef inner = solve_block(*a.block, *b.block);
  return inner ? make_tensor({a.dims[1]}, inner, false) : nullptr;
}

Typing type_solve(const Type& a, const Type& b) {
  if (!numeric_tensor(a) || a.order() != 2)
    return Typing::failure(
        SemanticKind::Type,
        "expected left operand of solve operation to be a matrix but got " + quoted(a));
  if (!numeric_tensor(b) || b.order() != 1 || b.row)
    return Typing::failure(
        SemanticKind::Type,
        "expected right operand of solve operation to be a column vector but got " + quoted(b));
  if (a.component() != b.component())
    return Typing::failure(SemanticKind::Type, "cannot solve with a matrix of type " + quoted(a) +
                                                   " and a vector of type " + quoted(b) +
                                                   " of a different component type");
  TypeRef x = solve_block(a, b);
  if (!x)
    return Typing::failure(SemanticKind::Dimension,
                           "solve operation cannot be performed on a matrix of type " + quoted(a) +
                               " and a vector of type " + quoted(b));
  return Typing::success(x);
}

Typing type_boolean(Op op, const Type& l, const Type& r) {
  const char* name = op == Op::And ? "and" : op == Op::Or ? "or" : "xor";
  if (!is_bool_scalar(l))
    return Typing::failure(SemanticKind::Type,
                           std::string("expected left operand of boolean operation '") + name +
                               "' to be a boolean but got " + quoted(l));
  if (!is_bool_scalar(r))
    return Typing::failure(SemanticKind::Type,
                           std::string("expected right operand of boolean operation '") + name +
                               "' to be a boolean but got " + quoted(r));
  return Typing::success(make_scalar(ScalarKind::Bool));
}

// Swaps the dimensions of a matrix and of its blocks, recursively.
TypeRef transpose_matrix(const Type& t) {
  if (t.kind != Type::Kind::Tensor) return make_scalar(t.scalar);
  TypeRef block = t.block ? transpose_matrix(*t.block) : nullptr;
  return make_tensor({t.dims[1], t.dims[0]}, block, false);
}

bool ordering_allowed(ScalarKind k) {
  return k == ScalarKind::Int || k == ScalarKind::Float || k == ScalarKind::String;
}

}  // namespace

Typing type_binary(ast::Binary::Op op, const Type& l, const Type& r) {
  switch (op) {
    case Op::Add:
    case Op::Sub:
    case Op::ElemMul:
    case Op::ElemDiv: return type_elementwise(op, l, r);
    case Op::Mul: return type_multiply(l, r);
    case Op::Div: return type_divide(l, r);
    case Op::LeftDiv: return type_solve(l, r);
    case Op::Pow:
      return Typing::failure(SemanticKind::None,
                             "the '^' operator is not supported; use pow(a, b)");
    case Op::And:
    case Op::Or:
    case Op::Xor: return type_boolean(op, l, r);
  }
  return Typing::failure(SemanticKind::None, "unknown binary operator");
}

Typing type_unary(ast::Unary::Op op, const Type& operand) {
  if (op == ast::Unary::Op::Not) {
    if (!is_bool_scalar(operand))
      return Typing::failure(SemanticKind::Type,
                             "expected a boolean operand of 'not' but got " + quoted(operand));
    return Typing::success(make_scalar(ScalarKind::Bool));
  }
  if (!numeric_tensor(operand))
    return Typing::failure(
        SemanticKind::Type,
        "expected operand of tensor negation to be a numeric tensor but got " + quoted(operand));
  return Typing::success(copy_of(operand));
}

Typing type_transpose(const Type& operand) {
  if (!operand.is_tensor() || operand.order() > 2)
    return Typing::failure(
        SemanticKind::Type,
        "operand of tensor transpose must be a tensor of order 2 or less but got " +
            quoted(operand));
  if (operand.is_scalar()) return Typing::success(make_scalar(operand.scalar));
  // A vector's blocks stay columns; only the outer orientation flips.
  if (operand.order() == 1)
    return Typing::success(make_tensor(operand.dims, operand.block, !operand.row));
  return Typing::success(transpose_matrix(operand));
}

Typing type_compare(ast::Compare::Op op, const Type& l, const Type& r) {
  for (const Type* t : {&l, &r})
    if (!t->is_scalar())
      return Typing::failure(SemanticKind::Type,
                             "comparison operations can only be performed on scalar values, "
                             "not values of type " +
                                 quoted(*t));
  if (l.scalar != r.scalar)
    return Typing::failure(
        SemanticKind::Type,
        "value of type " + quoted(l) + " cannot be compared to value of type " + quoted(r));
  bool equality = op == ast::Compare::Op::Eq || op == ast::Compare::Op::Ne;
  if (!equality && !ordering_allowed(l.scalar))
    return Typing::failure(SemanticKind::Type, std::string("values of type ") + quoted(l) +
                                                   " cannot be ordered with '" +
                                                   compare_spelling(op) + "'");
  return Typing::success(make_scalar(ScalarKind::Bool));
}

}  // namespace simit::frontend
