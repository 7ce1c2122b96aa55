// The abstract syntax tree. The parser builds it; the checker annotates it (types,
// resolved declarations, frame slots) and from then on it is read-only.
#pragma once

#include <complex>
#include <memory>
#include <string>
#include <vector>

#include "frontend/intrinsics.h"
#include "frontend/source.h"
#include "frontend/types.h"

namespace simit::frontend::ast {

// One list of node kinds; the enum, the visitor dispatch and the printers derive from it.
// The entry lists are laid out by hand.
// clang-format off
#define SIMIT_EXPR_NODES(X)                                                       \
  X(IntLit) X(FloatLit) X(BoolLit) X(StringLit) X(ComplexLit) X(DenseLit)         \
  X(VarRef) X(Call) X(TensorRead) X(TupleRead) X(FieldRead) X(SetRead) X(Unary)   \
  X(Binary) X(Compare) X(Transpose) X(Map)
#define SIMIT_STMT_NODES(X)                                                       \
  X(VarDecl) X(IvarDecl) X(Assign) X(ExprStmt) X(If) X(While) X(DoWhile)          \
  X(ForRange) X(ForSet) X(Print) X(Apply)
#define SIMIT_TYPE_NODES(X)                                                       \
  X(ScalarTypeExpr) X(TensorTypeExpr) X(NamedTypeExpr) X(SetTypeExpr)            \
  X(GridTypeExpr) X(TupleTypeExpr) X(OpaqueTypeExpr)
#define SIMIT_DECL_NODES(X) X(ElementDecl) X(ExternDecl) X(ConstDecl) X(FuncDecl) X(TestDecl)
#define SIMIT_AST_NODES(X) \
  SIMIT_EXPR_NODES(X) SIMIT_STMT_NODES(X) SIMIT_TYPE_NODES(X) SIMIT_DECL_NODES(X)
// clang-format on

enum class NodeKind {
#define SIMIT_NODE_ENUM(n) n,
  SIMIT_AST_NODES(SIMIT_NODE_ENUM)
#undef SIMIT_NODE_ENUM
};
const char* node_kind_name(NodeKind k);

struct Node {
  explicit Node(NodeKind k, SourceSpan s) : kind(k), span(s) {}
  virtual ~Node() = default;
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const NodeKind kind;
  SourceSpan span;

  template <class T>
  bool is() const {
    return kind == T::kKind;
  }
  template <class T>
  T* as() {
    return kind == T::kKind ? static_cast<T*>(this) : nullptr;
  }
  template <class T>
  const T* as() const {
    return kind == T::kKind ? static_cast<const T*>(this) : nullptr;
  }
};

#define SIMIT_NODE_KIND(n) static constexpr NodeKind kKind = NodeKind::n;

// ---------------------------------------------------------------------------
// Resolved entities (owned by Program, referenced from nodes)

struct FuncDecl;

// Everything a name can denote as a value (LANGUAGE.md §4.1's value namespace).
struct Variable {
  enum class Kind {
    Extern,
    GlobalConst,
    Param,
    Result,
    Local,
    Implicit,
    LoopVar,
    IndexVar,
    Generic
  };
  Kind kind = Kind::Local;
  std::string name;
  SourceSpan span;                 // where it is declared
  TypeRef type;                    // sets and generic parameters have set / no type
  bool writable = false;           // access mode of §4.6.2
  bool inout = false;              // Param only
  bool ranged = false;             // Generic only: declared `0:N`
  const FuncDecl* func = nullptr;  // owning function (null for globals)
  // Interpreter storage: index into the owning function's frame, or into the program's
  // globals for Extern/GlobalConst.
  int slot = -1;
};

// ---------------------------------------------------------------------------
// Types as written

struct TypeExpr : Node {
  using Node::Node;
  TypeRef type;  // resolved by the checker
};
using TypeExprPtr = std::unique_ptr<TypeExpr>;

// `3` or `nodes` or `N` inside `[...]` of a tensor type, or an explicit generic argument.
struct IndexSetExpr {
  SourceSpan span;
  bool is_int = false;
  long long value = 0;
  std::string name;
  IndexSet resolved;  // by the checker
};

struct ScalarTypeExpr : TypeExpr {
  SIMIT_NODE_KIND(ScalarTypeExpr)
  ScalarTypeExpr(SourceSpan s, ScalarKind k) : TypeExpr(kKind, s), scalar(k) {}
  ScalarKind scalar;
};

struct TensorTypeExpr : TypeExpr {
  SIMIT_NODE_KIND(TensorTypeExpr)
  enum class Spelling { Tensor, Vector, Matrix };
  explicit TensorTypeExpr(SourceSpan s) : TypeExpr(kKind, s) {}
  Spelling spelling = Spelling::Tensor;
  std::vector<IndexSetExpr> dims;  // empty: `tensor(float)`, identical to the block
  TypeExprPtr block;               // ScalarTypeExpr or TensorTypeExpr
  bool transposed = false;         // trailing `'`
};

// An element type named by identifier.
struct NamedTypeExpr : TypeExpr {
  SIMIT_NODE_KIND(NamedTypeExpr)
  NamedTypeExpr(SourceSpan s, std::string n) : TypeExpr(kKind, s), name(std::move(n)) {}
  std::string name;
  const struct ElementDecl* element = nullptr;  // by the checker
};

struct SetTypeExpr : TypeExpr {
  SIMIT_NODE_KIND(SetTypeExpr)
  explicit SetTypeExpr(SourceSpan s) : TypeExpr(kKind, s) {}
  std::string element;
  SourceSpan element_span;
  std::vector<IndexSetExpr> endpoints;  // names; the shorthand `(V * n)` is expanded
  bool shorthand = false;               // written as `(V * n)` (kept for printing)
  long long shorthand_count = 0;        // n as written (may be < 1: a checker error)
};

struct GridTypeExpr : TypeExpr {
  SIMIT_NODE_KIND(GridTypeExpr)
  explicit GridTypeExpr(SourceSpan s) : TypeExpr(kKind, s) {}
  long long dims = 0;
  std::string element;
  SourceSpan element_span;
  IndexSetExpr point_set;
};

struct TupleTypeExpr : TypeExpr {
  SIMIT_NODE_KIND(TupleTypeExpr)
  explicit TupleTypeExpr(SourceSpan s) : TypeExpr(kKind, s) {}
  bool named = false;
  // unnamed `(E * n)`: one element name and `count`; named: parallel lists
  std::vector<std::string> names;
  std::vector<std::string> elements;
  std::vector<SourceSpan> element_spans;
  long long count = 0;
};

struct OpaqueTypeExpr : TypeExpr {
  SIMIT_NODE_KIND(OpaqueTypeExpr)
  explicit OpaqueTypeExpr(SourceSpan s) : TypeExpr(kKind, s) {}
};

// ---------------------------------------------------------------------------
// Expressions

struct Call;
struct Expr : Node {
  using Node::Node;
  TypeRef type;           // by the checker (Void / Multi for calls and maps)
  bool writable = false;  // by the checker: a place that may be assigned or passed inout
  // By the hoisting pass (frontend/hoisting.h), on root expressions only: the nested
  // user-function calls that run before the expression is computed, in order.
  std::vector<const Call*> hoisted;
};
using ExprPtr = std::unique_ptr<Expr>;

struct IntLit : Expr {
  SIMIT_NODE_KIND(IntLit)
  IntLit(SourceSpan s, long long v) : Expr(kKind, s), value(v) {}
  long long value;
};

struct FloatLit : Expr {
  SIMIT_NODE_KIND(FloatLit)
  FloatLit(SourceSpan s, double v) : Expr(kKind, s), value(v) {}
  double value;
};

struct BoolLit : Expr {
  SIMIT_NODE_KIND(BoolLit)
  BoolLit(SourceSpan s, bool v) : Expr(kKind, s), value(v) {}
  bool value;
};

struct StringLit : Expr {
  SIMIT_NODE_KIND(StringLit)
  StringLit(SourceSpan s, std::string v) : Expr(kKind, s), value(std::move(v)) {}
  std::string value;  // decoded
};

struct ComplexLit : Expr {
  SIMIT_NODE_KIND(ComplexLit)
  ComplexLit(SourceSpan s, std::complex<double> v) : Expr(kKind, s), value(v) {}
  std::complex<double> value;
};

// `[1.0, 2.0; 3.0, 4.0]`, nested literals flattened row-major. Signs are folded in.
struct DenseLit : Expr {
  SIMIT_NODE_KIND(DenseLit)
  explicit DenseLit(SourceSpan s) : Expr(kKind, s) {}
  ScalarKind component = ScalarKind::Float;  // Int, Float or Complex
  std::vector<int> shape;                    // one entry per dimension, outermost first
  std::vector<long long> ints;
  std::vector<double> floats;
  std::vector<std::complex<double>> complexes;
  bool column = false;  // an order-1 literal with `'` applied (folded)
  // Set by the parser when nested literals disagree in shape or kind; the checker
  // reports it (a semantic error: "mismatched dimension sizes" / "mismatched element types").
  std::string shape_error;
};

struct VarRef : Expr {
  SIMIT_NODE_KIND(VarRef)
  VarRef(SourceSpan s, std::string n) : Expr(kKind, s), name(std::move(n)) {}
  std::string name;
  const Variable* var = nullptr;  // by the checker
};

struct Call : Expr {
  SIMIT_NODE_KIND(Call)
  explicit Call(SourceSpan s) : Expr(kKind, s) {}
  std::string callee;
  SourceSpan callee_span;
  std::vector<IndexSetExpr> generic_args;  // explicit `<...>`
  std::vector<ExprPtr> args;
  // by the checker: exactly one of these is set
  const FuncDecl* func = nullptr;
  Intrinsic intrinsic = Intrinsic::None;
  std::vector<IndexSet> bindings;  // one per generic parameter of the callee
};

// `A(i, j)`; a null index is a slice `:`.
struct TensorRead : Expr {
  SIMIT_NODE_KIND(TensorRead)
  explicit TensorRead(SourceSpan s) : Expr(kKind, s) {}
  ExprPtr base;
  std::vector<ExprPtr> indices;
  bool index_notation = false;  // by the checker: some index is an ivar
  // By the assembly-write pass (frontend/assembly_writes.h), on assignment targets only:
  // the function result this write assembles into (a system vector or matrix), or -1.
  int assembles_result = -1;
};

// `t(k)` on an unnamed tuple, or `t.name` on a named one.
struct TupleRead : Expr {
  SIMIT_NODE_KIND(TupleRead)
  explicit TupleRead(SourceSpan s) : Expr(kKind, s) {}
  ExprPtr base;           // a VarRef to a tuple parameter
  ExprPtr index;          // unnamed form
  std::string member;     // named form (index is null)
  int member_index = -1;  // named form, by the checker
};

struct FieldRead : Expr {
  SIMIT_NODE_KIND(FieldRead)
  explicit FieldRead(SourceSpan s) : Expr(kKind, s) {}
  ExprPtr base;
  std::string field;
  SourceSpan field_span;
  int field_index = -1;  // by the checker: index in the element's field list
  bool of_set = false;   // by the checker: `S.f`, the global vector view
};

// `g[0;1]` (a grid link) or `P[1, 0]` (a point at an offset).
struct SetRead : Expr {
  SIMIT_NODE_KIND(SetRead)
  explicit SetRead(SourceSpan s) : Expr(kKind, s) {}
  ExprPtr base;
  std::vector<ExprPtr> first;   // before `;`
  std::vector<ExprPtr> second;  // after `;`
  bool has_semicolon = false;
};

struct Unary : Expr {
  SIMIT_NODE_KIND(Unary)
  enum class Op { Neg, Plus, Not };
  Unary(SourceSpan s, Op o, ExprPtr e) : Expr(kKind, s), op(o), operand(std::move(e)) {}
  Op op;
  ExprPtr operand;
};

struct Binary : Expr {
  SIMIT_NODE_KIND(Binary)
  enum class Op { Add, Sub, Mul, Div, LeftDiv, ElemMul, ElemDiv, Pow, And, Or, Xor };
  Binary(SourceSpan s, Op o, ExprPtr l, ExprPtr r)
      : Expr(kKind, s), op(o), lhs(std::move(l)), rhs(std::move(r)) {}
  Op op;
  ExprPtr lhs, rhs;
};
const char* binary_op_spelling(Binary::Op op);

// A comparison chain `a < b <= c`: operands.size() == ops.size() + 1.
struct Compare : Expr {
  SIMIT_NODE_KIND(Compare)
  enum class Op { Eq, Ne, Lt, Gt, Le, Ge };
  explicit Compare(SourceSpan s) : Expr(kKind, s) {}
  std::vector<ExprPtr> operands;
  std::vector<Op> ops;
};
const char* compare_op_spelling(Compare::Op op);

struct Transpose : Expr {
  SIMIT_NODE_KIND(Transpose)
  Transpose(SourceSpan s, ExprPtr e) : Expr(kKind, s), operand(std::move(e)) {}
  ExprPtr operand;
};

// The parts shared by `map ... to S` and `apply ... to S`.
struct Assembly {
  std::string func;
  SourceSpan func_span;
  std::vector<IndexSetExpr> generic_args;
  std::vector<ExprPtr> args;  // partial arguments
  std::string target;
  SourceSpan target_span;
  // by the checker
  const FuncDecl* callee = nullptr;
  const Variable* target_set = nullptr;
  std::vector<IndexSet> bindings;
  bool pass_endpoints = false;  // the function takes the endpoint tuple
};

struct Map : Expr {
  SIMIT_NODE_KIND(Map)
  explicit Map(SourceSpan s) : Expr(kKind, s) {}
  Assembly assembly;
  std::string through;  // empty when absent
  SourceSpan through_span;
  const Variable* through_set = nullptr;  // by the checker
  bool reduce = false;
};

// ---------------------------------------------------------------------------
// Statements

struct Stmt : Node {
  using Node::Node;
  // By the system-statement pass (frontend/system_statements.h): computes on system
  // tensors without calling user code, so a compiled executor may run it as a whole.
  bool system_level = false;
  // By the same pass: assigns scalars from scalars without calling user code (`var k = 0;`),
  // so it may join a run of system-level statements.
  bool scalar_level = false;
};
using StmtPtr = std::unique_ptr<Stmt>;
using Block = std::vector<StmtPtr>;

// `var x : T = e;`, `const x = e;` (also global constants, see ConstDecl).
struct VarDecl : Stmt {
  SIMIT_NODE_KIND(VarDecl)
  explicit VarDecl(SourceSpan s) : Stmt(kKind, s) {}
  bool is_const = false;
  std::string name;
  SourceSpan name_span;
  TypeExprPtr declared;     // may be null
  ExprPtr init;             // may be null (var only)
  Variable* var = nullptr;  // by the checker
};

struct IvarDecl : Stmt {
  SIMIT_NODE_KIND(IvarDecl)
  IvarDecl(SourceSpan s, std::string n) : Stmt(kKind, s), name(std::move(n)) {}
  std::string name;
  Variable* var = nullptr;
};

// `a = e;`, `a, b = f(x);`, and index-notation assignments `C(i,j) = A(i,k) * B(k,j);`.
struct Assign : Stmt {
  SIMIT_NODE_KIND(Assign)
  explicit Assign(SourceSpan s) : Stmt(kKind, s) {}
  std::vector<ExprPtr> targets;
  ExprPtr value;
  // by the checker
  std::vector<Variable*> declares;  // per target: the implicit local it declares, or null
  bool index_notation = false;
  std::vector<const Variable*> free_vars;       // index notation: ivars of the left side
  std::vector<const Variable*> reduction_vars;  // index notation: ivars only on the right
  // By the index-range pass (frontend/index_ranges.h), index notation only: the loop
  // variables (each once; a reduction variable is one the left side does not use) and the
  // reads whose dimensions give their ranges, left side first.
  std::vector<const Variable*> loop_free, loop_reduction;
  std::vector<const struct TensorRead*> ranging_reads;
};

struct ExprStmt : Stmt {
  SIMIT_NODE_KIND(ExprStmt)
  ExprStmt(SourceSpan s, ExprPtr e) : Stmt(kKind, s), expr(std::move(e)) {}
  ExprPtr expr;
};

struct If : Stmt {
  SIMIT_NODE_KIND(If)
  explicit If(SourceSpan s) : Stmt(kKind, s) {}
  std::vector<ExprPtr> conditions;  // if, then each elif
  std::vector<Block> branches;      // same length as conditions
  Block else_branch;
  bool has_else = false;
};

struct While : Stmt {
  SIMIT_NODE_KIND(While)
  explicit While(SourceSpan s) : Stmt(kKind, s) {}
  ExprPtr condition;
  Block body;
};

struct DoWhile : Stmt {
  SIMIT_NODE_KIND(DoWhile)
  explicit DoWhile(SourceSpan s) : Stmt(kKind, s) {}
  Block body;
  ExprPtr condition;
};

struct ForRange : Stmt {
  SIMIT_NODE_KIND(ForRange)
  explicit ForRange(SourceSpan s) : Stmt(kKind, s) {}
  std::string var_name;
  SourceSpan var_span;
  ExprPtr lo, hi;
  Block body;
  Variable* var = nullptr;
};

// `for e in S` over a set or a generic parameter.
struct ForSet : Stmt {
  SIMIT_NODE_KIND(ForSet)
  explicit ForSet(SourceSpan s) : Stmt(kKind, s) {}
  std::string var_name;
  SourceSpan var_span;
  std::string domain;
  SourceSpan domain_span;
  Block body;
  Variable* var = nullptr;
  const Variable* domain_var = nullptr;  // the set or generic parameter
};

// `print`, `println` and `error` (docs/error_statement.md) share their argument list: an
// error statement formats its message exactly as println would print it, then stops the run.
struct Print : Stmt {
  SIMIT_NODE_KIND(Print)
  enum class Mode { Print, Println, Error };
  explicit Print(SourceSpan s) : Stmt(kKind, s) {}
  Mode mode = Mode::Print;
  std::vector<ExprPtr> args;
  bool newline() const { return mode != Mode::Print; }
  bool is_error() const { return mode == Mode::Error; }
};

struct Apply : Stmt {
  SIMIT_NODE_KIND(Apply)
  explicit Apply(SourceSpan s) : Stmt(kKind, s) {}
  Assembly assembly;
};

// ---------------------------------------------------------------------------
// Program elements

struct Decl : Node {
  using Node::Node;
};
using DeclPtr = std::unique_ptr<Decl>;

struct FieldDecl {
  std::string name;
  SourceSpan span;
  TypeExprPtr type_expr;
  TypeRef type;  // by the checker
};

struct ElementDecl : Decl {
  SIMIT_NODE_KIND(ElementDecl)
  explicit ElementDecl(SourceSpan s) : Decl(kKind, s) {}
  std::string name;
  SourceSpan name_span;
  std::vector<FieldDecl> fields;
  int field_index(const std::string& n) const;  // -1 when absent
};

struct ExternDecl : Decl {
  SIMIT_NODE_KIND(ExternDecl)
  explicit ExternDecl(SourceSpan s) : Decl(kKind, s) {}
  std::string name;
  SourceSpan name_span;
  TypeExprPtr type_expr;
  Variable* var = nullptr;
};

struct ConstDecl : Decl {
  SIMIT_NODE_KIND(ConstDecl)
  explicit ConstDecl(SourceSpan s) : Decl(kKind, s) {}
  std::unique_ptr<VarDecl> decl;  // is_const == true; its var is a GlobalConst
};

struct GenericParam {
  std::string name;
  SourceSpan span;
  bool ranged = false;  // `0:N`
  Variable* var = nullptr;
};

struct Param {
  std::string name;
  SourceSpan span;
  bool inout = false;
  TypeExprPtr type_expr;
  Variable* var = nullptr;
};

struct FuncDecl : Decl {
  SIMIT_NODE_KIND(FuncDecl)
  explicit FuncDecl(SourceSpan s) : Decl(kKind, s) {}
  bool exported = false;
  bool is_extern = false;  // `extern func`: no body
  std::string name;
  SourceSpan name_span;
  std::vector<GenericParam> generics;
  std::vector<Param> params;
  std::vector<Param> results;
  Block body;
  int frame_size = 0;  // by the checker: slots for generics, params, results and locals
  // By the extern-use pass (frontend/extern_uses.h): the externs it needs bound.
  std::vector<const Variable*> extern_uses;
};

// `%! f(args) == expected;`
struct TestDecl : Decl {
  SIMIT_NODE_KIND(TestDecl)
  explicit TestDecl(SourceSpan s) : Decl(kKind, s) {}
  std::string func;
  SourceSpan func_span;
  std::vector<ExprPtr> args;
  ExprPtr expected;
  const FuncDecl* callee = nullptr;  // by the checker (null: unknown function)
};

struct Program {
  std::vector<DeclPtr> decls;
  // by the checker
  std::vector<std::unique_ptr<Variable>> variables;  // every Variable of the program
  std::vector<const Variable*> globals;              // externs and constants, by slot
  const FuncDecl* find_func(const std::string& name) const;
};

#undef SIMIT_NODE_KIND

// The children of each expression kind that has any, in evaluation order (`n` is the node);
// frontend/ast_walk.h generates the child walk from it.
#define SIMIT_EXPR_CHILDREN(X)          \
  X(Unary, n.operand)                   \
  X(Transpose, n.operand)               \
  X(Binary, n.lhs, n.rhs)               \
  X(Compare, n.operands)                \
  X(Call, n.args)                       \
  X(TensorRead, n.base, n.indices)      \
  X(FieldRead, n.base)                  \
  X(TupleRead, n.base, n.index)         \
  X(SetRead, n.base, n.first, n.second) \
  X(Map, n.assembly.args)

// The root expressions and the nested blocks of each statement kind that has any (`n` is the
// statement); frontend/ast_walk.h generates the statement walk from it.
#define SIMIT_STMT_PARTS(X)                          \
  X(VarDecl, (n.init), ())                           \
  X(Assign, (n.value, n.targets), ())                \
  X(ExprStmt, (n.expr), ())                          \
  X(If, (n.conditions), (n.branches, n.else_branch)) \
  X(While, (n.condition), (n.body))                  \
  X(DoWhile, (n.condition), (n.body))                \
  X(ForRange, (n.lo, n.hi), (n.body))                \
  X(ForSet, (), (n.body))                            \
  X(Print, (n.args), ())                             \
  X(Apply, (n.assembly.args), ())

}  // namespace simit::frontend::ast
