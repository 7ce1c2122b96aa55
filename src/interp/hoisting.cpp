// Calls nested inside an expression run before the expression is computed, in textual
// order (LANGUAGE.md §6.10): the original hoists them into temporaries. This is observable
// through inout arguments, e.g. in `x + take(x)` the read of x sees take's write. The
// frontend's hoisting pass lists the calls; here they run.
#include "interp/frame.h"
#include "interp/interpreter.h"

namespace simit::interp {

namespace ast = frontend::ast;

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

void Interpreter::HoistScope::run(const ast::Expr& root) {
  Interpreter& in = in_;
  active_ = true;
  saved_base_ = in.hoist_base_;
  in.hoist_base_ = in.hoisted_.size();
  try {
    for (const ast::Call* c : root.hoisted) {
      Value v = in.eval_user_call(*c);
      in.hoisted_.emplace_back(c, std::move(v));
    }
  } catch (...) {
    in.hoisted_.resize(in.hoist_base_);
    in.hoist_base_ = saved_base_;
    throw;
  }
}

void Interpreter::HoistScope::finish() {
  in_.hoisted_.resize(in_.hoist_base_);
  in_.hoist_base_ = saved_base_;
}

}  // namespace simit::interp
