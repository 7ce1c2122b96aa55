// Private state of the type checker (scopes, the function being checked, index-notation
// bookkeeping) and the type helpers shared by the checker_*.cpp files.
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "frontend/ast.h"
#include "frontend/diagnostics.h"
#include "frontend/types.h"

namespace simit::frontend::checker_detail {

// Nested value scopes of §4.6.1; the first frame is the global scope.
class Scopes {
 public:
  void push() { frames_.emplace_back(); }
  void pop() { frames_.pop_back(); }
  ast::Variable* lookup(const std::string& name) const;
  ast::Variable* lookup_innermost(const std::string& name) const;
  void declare(ast::Variable* v) { frames_.back()[v->name] = v; }

 private:
  std::vector<std::unordered_map<std::string, ast::Variable*>> frames_;
};

// Where a type is written; §5.7 restricts the kinds allowed in each position.
enum class TypePos { Field, Extern, GlobalConst, Param, Result, Local };

// What generic parameters and set parameters of a callee are bound to at one call.
using Subst = std::unordered_map<const ast::Variable*, IndexSet>;

// ---- type helpers (checker_types.cpp) ----
TypeRef element_type(const ast::ElementDecl* decl, IndexSet source, bool has_source);
// The loop variable of `for m in N` over a plain generic parameter: an element of an
// unknown set (Element kind with a null declaration).
TypeRef generic_element_type(const ast::Variable* generic);
TypeRef with_source(const TypeRef& element, IndexSet source);
TypeRef tuple_type(std::vector<TypeRef> members, std::vector<std::string> names);
TypeRef substitute(const TypeRef& t, const Subst& s);
IndexSet substitute(const IndexSet& d, const Subst& s);
// Type equality of §10.2 over every kind (tensors defer to types_equal).
bool same_type(const Type& a, const Type& b);
bool is_single_value(const Type& t);
bool is_tensor_or_opaque(const Type& t);
bool is_int(const Type& t);
bool is_bool(const Type& t);
std::string type_name(const Type& t);
std::string quoted(const Type& t);
std::string index_set_name(const IndexSet& d);
// Whether the set variable `v` has a set type (a set extern or set parameter).
bool is_set_var(const ast::Variable* v);
// A dimension indexed by `int`s: a fixed size or a ranged generic parameter `0:N`.
bool is_int_dim(const IndexSet& d);
// A dense tensor's components are counted in 32-bit ints by its users: at most 2^31 - 1.
inline constexpr uint64_t kMaxTensorComponents = 0x7fffffff;
uint64_t fixed_components(const Type& t);

// What the checker remembers about a function once its header (and body) are checked.
struct FuncInfo {
  bool signature_ok = true;
  bool body_ok = true;  // its body checked without diagnostics
  // Reads a result, or assigns one whole: illegal when the function is mapped (Q10/Q19).
  bool misuses_result = false;
  SourceSpan misuse_span;
  std::string misused_result;
};

// The argument list a call or map hands to a user function, already typed.
struct ArgList {
  std::vector<TypeRef> types;
  std::vector<const ast::Expr*> exprs;         // null for implicit map arguments
  std::vector<const ast::Variable*> set_vars;  // the set a set-typed argument names
};

class Checker {
 public:
  Checker(ast::Program& program, Diagnostics& diags) : program_(program), diags_(&diags) {}
  void run();
  // checker_debug.cpp: a debugger expression in the scope of `func` (may be null) with
  // `locals` visible, outermost first (frontend/debug_expr.h).
  TypeRef check_debug_expr(ast::Expr& e, const ast::FuncDecl* func,
                           const std::vector<const ast::Variable*>& locals);

 private:
  // checker.cpp: program elements
  void check_decl(ast::Decl& d);
  void check_element(ast::ElementDecl& e);
  void check_extern(ast::ExternDecl& e);
  void check_global_const(ast::ConstDecl& c);
  void check_func(ast::FuncDecl& f);
  void declare_generics(ast::FuncDecl& f, FuncInfo& info);
  void declare_params(std::vector<ast::Param>& params, ast::Variable::Kind kind, FuncInfo& info);
  void check_body(ast::FuncDecl& f, FuncInfo& info);
  void infer_sources(ast::FuncDecl& f, FuncInfo& info);
  void check_test(ast::TestDecl& t);
  ast::Variable* new_variable(ast::Variable::Kind kind, const std::string& name, SourceSpan span,
                              TypeRef type, bool writable);
  void error(SemanticKind kind, SourceSpan span, std::string message);
  // Reports an undeclared name once: later uses of the same name would only repeat it.
  void undeclared(const std::string& what, const std::string& name, SourceSpan span);

  // checker_types.cpp: types as written
  TypeRef resolve_type(ast::TypeExpr& t, TypePos pos);
  TypeRef resolve_type_expr(ast::TypeExpr& t);
  TypeRef resolve_tensor_type(ast::TensorTypeExpr& t);
  TypeRef resolve_set_type(ast::SetTypeExpr& t);
  TypeRef resolve_grid_type(ast::GridTypeExpr& t);
  TypeRef resolve_tuple_type(ast::TupleTypeExpr& t);
  const ast::ElementDecl* resolve_element(const std::string& name, SourceSpan span);
  bool resolve_dim(ast::IndexSetExpr& d, bool allow_generic);
  bool resolve_set_name(ast::IndexSetExpr& d);
  bool check_position(const ast::TypeExpr& t, const Type& type, TypePos pos);

  // checker_exprs.cpp: expressions
  TypeRef check_expr(ast::Expr& e);
  TypeRef dispatch_expr(ast::Expr& e);
  TypeRef check_value(ast::Expr& e, const char* what);
  TypeRef check_place(ast::Expr& e);
  TypeRef check_var_ref(ast::VarRef& r, bool read);
  TypeRef check_dense(ast::DenseLit& d);
  TypeRef check_unary(ast::Unary& u);
  TypeRef check_binary(ast::Binary& b);
  TypeRef check_compare(ast::Compare& c);
  TypeRef check_transpose(ast::Transpose& t);
  TypeRef type_tensor_read(ast::TensorRead& r, const TypeRef& base);
  TypeRef check_index(ast::TensorRead& r, size_t i, const IndexSet& dim, bool* is_ivar);
  bool check_set_index(ast::TensorRead& r, ast::Expr& index, const Type& t, const IndexSet& dim);
  void infer_source(ast::TensorRead& r, ast::Expr& index, const IndexSet& dim);
  TypeRef slice_type(const ast::TensorRead& r, const Type& base);
  TypeRef type_field_read(ast::FieldRead& f, const TypeRef& base);
  TypeRef type_tuple_read(ast::TupleRead& t, const TypeRef& base);
  TypeRef check_set_read(ast::SetRead& s);
  bool check_grid_indices(ast::SetRead& s, size_t expected, bool link);
  int grid_dims_of(const ast::Variable* point_set) const;
  bool operands_ok(ast::Expr& at, const std::vector<const Type*>& operands);
  ast::Variable* ivar_named(const ast::Expr& e) const;
  bool mentions_ivar(const ast::Expr& e) const;

  // checker_calls.cpp: calls, generics and assembly
  TypeRef check_call(ast::Call& c);
  TypeRef check_intrinsic_call(ast::Call& c, Intrinsic id);
  bool check_args(std::vector<ast::ExprPtr>& args, ArgList& out);
  bool resolve_generic_args(std::vector<ast::IndexSetExpr>& args, std::vector<IndexSet>& out);
  bool bind_generics(const ast::FuncDecl& f, const std::vector<IndexSet>& explicit_args,
                     const ArgList& args, SourceSpan at, Subst& s, std::vector<IndexSet>& bindings);
  bool report_order_mismatch(const ast::FuncDecl& f, const ArgList& args, const Subst& s,
                             SourceSpan at);
  void unify(const Type& param, const Type& arg, const ast::FuncDecl& f, Subst& s);
  bool check_arg_types(const ast::FuncDecl& f, const ArgList& args, const Subst& s, SourceSpan at,
                       bool is_map);
  TypeRef result_type(const ast::FuncDecl& f, const Subst& s, SourceSpan at);
  TypeRef check_map(ast::Map& m);
  bool check_assembly(ast::Assembly& a, const std::string& through, SourceSpan through_span,
                      const ast::Variable** through_var, SourceSpan at, Subst& s, bool is_apply);
  bool check_partial_args(ast::Assembly& a, ArgList& args);
  bool assembly_args(ast::Assembly& a, const ast::FuncDecl& f, const ast::Variable* grid,
                     SourceSpan at, ArgList& args);
  const ast::Variable* lookup_set(const std::string& name, SourceSpan span, bool is_target);
  bool check_map_results(const ast::Map& m, const ast::FuncDecl& f, const Subst& s);

  // checker_stmts.cpp: statements
  void check_block(ast::Block& b);
  void check_scoped_block(ast::Block& b);
  void check_stmt(ast::Stmt& s);
  void check_var_decl(ast::VarDecl& v);
  void check_ivar_decl(ast::IvarDecl& v);
  void check_assign(ast::Assign& a);
  void assign_target(ast::Assign& a, size_t i, const TypeRef& value);
  void declare_implicit(ast::Assign& a, size_t i, const TypeRef& value);
  void not_writable(const ast::Expr& target);
  bool check_assignable(SourceSpan at, const Type& target, const Type& value);
  void check_condition(ast::Expr& e);
  void check_for_range(ast::ForRange& f);
  void check_for_set(ast::ForSet& f);
  void check_print(ast::Print& p);
  void check_apply(ast::Apply& a);
  bool check_initializer(SourceSpan at, const Type& declared, const Type& value, bool is_const,
                         bool global);

  // checker_index.cpp: index-notation assignments (§7.2)
  void check_index_assign(ast::Assign& a);
  void record_ivar(const ast::Variable* v, const IndexSet& dim, SourceSpan at);

  ast::Program& program_;
  Diagnostics* diags_;  // redirected to a scratch list while inferring element sources
  Scopes scopes_;
  std::unordered_map<std::string, const ast::ElementDecl*> elements_;
  std::unordered_map<std::string, const ast::FuncDecl*> funcs_;      // visible so far
  std::unordered_map<std::string, const ast::FuncDecl*> all_funcs_;  // for `%!` tests
  std::unordered_map<const ast::FuncDecl*, FuncInfo> infos_;
  std::unordered_set<std::string> undeclared_;  // "<what> <name>" already reported
  ast::FuncDecl* func_ = nullptr;               // the function whose header or body is checked
  FuncInfo* info_ = nullptr;

  bool debug_expr_ = false;  // a debugger expression: an element compares as its index

  // Index notation of the assignment being checked.
  bool in_index_ = false;  // division banned, `*` multiplies components
  bool ivars_ok_ = false;  // an index variable may stand as a whole index here
  std::vector<std::pair<const ast::Variable*, IndexSet>> ivar_dims_;
  std::vector<const ast::Variable*>* ivar_sink_ = nullptr;  // ivars of the current side
};

}  // namespace simit::frontend::checker_detail
