// The system tracer's private state (class SystemTracer), shared by the trace/system_*.cpp
// files that define its member functions by concern: system_tracer.cpp (the run, its
// variables and their bindings), system_expressions.cpp and system_statements.cpp. Only
// jit/system_trace.h is public.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "frontend/ast.h"
#include "frontend/ast_walk.h"
#include "interp/exec_state.h"
#include "jit/ir_build.h"
#include "jit/loop_ir.h"
#include "jit/system_trace.h"
#include "jit/trace/abort_reasons.h"

namespace simit::jit::trace_detail {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::SourceSpan;
using frontend::Type;
using interp::Value;

inline ExprRef local(int l, Ty ty) {
  Expr e;
  e.kind = ExprKind::Local;
  e.ty = ty;
  e.slot = l;
  return make(e);
}

inline bool has_set_dim(const Type& t) {
  if (t.kind != Type::Kind::Tensor) return false;
  for (const IndexSet& d : t.dims)
    if (d.kind != IndexSet::Kind::Fixed) return true;
  return false;
}
inline bool is_vector(const Type& t) { return has_set_dim(t) && t.dims.size() == 1; }
inline bool is_matrix(const Type& t) { return has_set_dim(t) && t.dims.size() == 2; }
inline bool is_row(const ast::Expr& e) { return e.type && is_vector(*e.type) && e.type->row; }

// Lowers a run of system-level statements to a SystemTrace (jit/system_trace.h).
class SystemTracer {
 public:
  SystemTracer(const std::vector<const ast::Stmt*>& run, interp::ExecState& in, bool float32)
      : run_(run), in_(in), float32_(float32) {}

  TracedSystem run();

 private:
  struct Mat {
    int row_ptr, cols, values, rows, block;
    int64_t length;
  };

  // The run and its variables (system_tracer.cpp).
  void name(const ast::While* loop);
  void mark_binary32_vectors();
  void trace_loop(const ast::While& loop);
  void end_section();
  void collect();
  void collect_block(const ast::Block& body, const std::function<void(const ast::Expr&)>& expr);
  void collect_stmt(const ast::Stmt& s, const std::function<void(const ast::Expr&)>& expr);
  void note(const ast::Variable& v, const SourceSpan& at);
  void note_field(const ast::FieldRead& f);
  static std::pair<const ast::Variable*, int> field_key(const ast::FieldRead& f);
  int array(const ast::Variable* v, SystemBinding::Array::Part part, Ty ty, std::string name);
  int size(const ast::Variable* v, bool rows, int64_t n, int field = -1);

  // Expressions (system_expressions.cpp).
  int length_of(const ast::Expr& e);
  int group_of(const ast::Expr& e);
  ExprRef dot(const ast::Expr& u, const ast::Expr& v, const SourceSpan& at);
  ExprRef rounded(ExprRef v, const SourceSpan& at) const;
  bool single(int slot) const { return t_.arrays[static_cast<size_t>(slot)].single; }
  Ty scalar_ty(const ast::Expr& e);
  ExprRef scalar(const ast::Expr& e);
  ExprRef component(const ast::Expr& e);
  ExprRef load(int slot, const SourceSpan& at);
  static ExprRef element();

  // Statements, ops and checks (system_statements.cpp).
  void scalar_stmt(Stmt s);
  void push_op(VectorOp op, const SourceSpan& at);
  void set_local(int l, ExprRef v, const SourceSpan& at);
  int temp(Ty ty);
  void stmt(const ast::Stmt& s);
  void assign(const ast::Variable& target, const ast::Expr& value, const SourceSpan& at);
  void check_has_value(const ast::Variable& v, const SourceSpan& at) const;
  void assign_field(const ast::FieldRead& target, const ast::Expr& value, const SourceSpan& at);
  void store_own_product(int slot, int n, const ast::Expr& value, const SourceSpan& at);
  bool is_product(const ast::Expr& value) const;
  void store_vector(int slot, int n, const ast::Expr& value, const SourceSpan& at);
  void store_pass(int slot, int n, ExprRef value, const SourceSpan& at);
  void spmv(const Mat& m, const ast::Expr& x, int y, int length, const SourceSpan& at);
  ExprRef product(const ast::Binary& b, const SourceSpan& at);
  int vector_operand(const ast::Expr& x, int n, const SourceSpan& at);
  int scratch(int n);
  void if_stmt(const ast::If& i, size_t from);
  static bool mentions_vector(const ast::Expr& e);
  static bool has_vectors(const ast::If& i);
  void guarded_if(const ast::If& i);
  void check_divisor(const ExprRef& d, const char* message, const SourceSpan& at);
  // An error statement: a check that always fails. Only the interpreter formats the message,
  // so a kernel that reaches it hands the whole loop back (TraceController::run_loop_kernel).
  void error_stmt(const SourceSpan& at) { check(iconst(0, Ty::Bool), "error statement", at); }
  void check(ExprRef ok, const char* message, const SourceSpan& at);

  const std::vector<const ast::Stmt*>& run_;
  interp::ExecState& in_;
  bool float32_ = false;
  size_t at_ = 0;                        // the statement of the run being collected or traced
  size_t first_field_write_ = SIZE_MAX;  // the first statement that writes a field
  using FieldKey = std::pair<const ast::Variable*, int>;  // a set and its field's index
  std::map<FieldKey, int> field_slot_, field_size_, field_block_;
  std::map<FieldKey, const frontend::Type*> field_type_;
  SystemTrace t_;
  std::vector<VectorOp>* ops_ = &t_.before;  // the section being traced
  SystemBinding b_;
  std::map<const ast::Variable*, int> scalar_local_, vector_slot_, size_of_, block_of_;
  std::map<const ast::Variable*, Mat> matrix_;
  std::map<std::pair<bool, int64_t>, int> sizes_;
  std::vector<int64_t> size_value_;  // per size: the length it was traced for
  int scratch_count_ = 0;
  std::set<const ast::Variable*> assigned_;  // vectors assigned so far outside any if
  std::vector<Stmt>* sink_ = nullptr;        // where scalar statements go inside an if's branch
  int guard_ = -1;            // the Bool local the ops traced now run under (guarded_if), or -1
  std::vector<Stmt> starts_;  // the section's sums' +0.0 starts, first in it
};

}  // namespace simit::jit::trace_detail
