// Calls nested inside an expression run before the expression is computed, in textual
// order (LANGUAGE.md §6.10): the original hoists them into temporaries. This is observable
// through inout arguments, e.g. in `x + take(x)` the read of x sees take's write.
#include "interp/ast_walk.h"
#include "interp/frame.h"
#include "interp/interpreter.h"

namespace simit::interp {

namespace ast = frontend::ast;

namespace {

// The user-function calls inside `e`, innermost first, left to right.
void collect_calls(const ast::Expr& e, std::vector<const ast::Call*>& out) {
  for_each_child(e, [&](const ast::Expr& c) { collect_calls(c, out); });
  if (const auto* call = e.as<ast::Call>(); call && call->func) out.push_back(call);
}

}  // namespace

void Interpreter::plan_root(const ast::Expr& root) {
  std::vector<const ast::Call*> calls;
  collect_calls(root, calls);
  // A call that is the whole expression runs last anyway; only nested ones need hoisting.
  if (!calls.empty() && calls.back() == &root) calls.pop_back();
  if (!calls.empty()) hoists_.emplace(&root, std::move(calls));
}

void Interpreter::plan_block(const ast::Block& block) {
  for (const auto& stmt : block) {
    const ast::Stmt& s = *stmt;
    switch (s.kind) {
      case ast::NodeKind::VarDecl:
        if (const auto& init = static_cast<const ast::VarDecl&>(s).init) plan_root(*init);
        break;
      case ast::NodeKind::Assign: {
        const auto& a = static_cast<const ast::Assign&>(s);
        plan_root(*a.value);
        for (const auto& t : a.targets) plan_root(*t);
        break;
      }
      case ast::NodeKind::ExprStmt: plan_root(*static_cast<const ast::ExprStmt&>(s).expr); break;
      case ast::NodeKind::If: {
        const auto& i = static_cast<const ast::If&>(s);
        for (const auto& c : i.conditions) plan_root(*c);
        for (const auto& b : i.branches) plan_block(b);
        plan_block(i.else_branch);
        break;
      }
      case ast::NodeKind::While: {
        const auto& w = static_cast<const ast::While&>(s);
        plan_root(*w.condition);
        plan_block(w.body);
        break;
      }
      case ast::NodeKind::DoWhile: {
        const auto& d = static_cast<const ast::DoWhile&>(s);
        plan_block(d.body);
        plan_root(*d.condition);
        break;
      }
      case ast::NodeKind::ForRange: {
        const auto& f = static_cast<const ast::ForRange&>(s);
        plan_root(*f.lo);
        plan_root(*f.hi);
        plan_block(f.body);
        break;
      }
      case ast::NodeKind::ForSet: plan_block(static_cast<const ast::ForSet&>(s).body); break;
      case ast::NodeKind::Print:
        for (const auto& a : static_cast<const ast::Print&>(s).args) plan_root(*a);
        break;
      case ast::NodeKind::Apply:
        for (const auto& a : static_cast<const ast::Apply&>(s).assembly.args) plan_root(*a);
        break;
      default: break;
    }
  }
}

void Interpreter::plan_hoisting() {
  for (const auto& decl : program_.decls)
    if (const auto* f = decl->as<ast::FuncDecl>()) plan_block(f->body);
}

bool Interpreter::take_hoisted(const ast::Call& c, Value& out) {
  for (size_t i = hoist_base_; i < hoisted_.size(); ++i) {
    if (hoisted_[i].first == &c) {
      out = hoisted_[i].second;  // a copy: index notation evaluates its right side repeatedly
      return true;
    }
  }
  return false;
}

Value Interpreter::eval_root(const ast::Expr& e) {
  HoistScope hoisted(*this, e);
  return eval(e);
}

Interpreter::HoistScope::HoistScope(Interpreter& in, const ast::Expr& root) : in_(in) {
  if (in.hoists_.empty()) return;  // the common case: no statement needs hoisting
  auto it = in.hoists_.find(&root);
  if (it == in.hoists_.end()) return;
  active_ = true;
  saved_base_ = in.hoist_base_;
  in.hoist_base_ = in.hoisted_.size();
  try {
    for (const ast::Call* c : it->second) {
      Value v = in.eval_user_call(*c);
      in.hoisted_.emplace_back(c, std::move(v));
    }
  } catch (...) {
    in.hoisted_.resize(in.hoist_base_);
    in.hoist_base_ = saved_base_;
    throw;
  }
}

Interpreter::HoistScope::~HoistScope() {
  if (!active_) return;
  in_.hoisted_.resize(in_.hoist_base_);
  in_.hoist_base_ = saved_base_;
}

}  // namespace simit::interp
