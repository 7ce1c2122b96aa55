// The interpreter's activation records (one slot per variable of a function, numbered by the
// checker), the bookkeeping of inout arguments of pending calls, and the inline reads of the
// evaluation loop (variables, operands).
#pragma once

#include <new>
#include <vector>

#include "frontend/ast.h"
#include "interp/interpreter.h"
#include "runtime/fault.h"

namespace simit::interp {

struct Interpreter::Frame {
  const frontend::ast::FuncDecl* func = nullptr;
  std::vector<Value> slots;
  // Where each slot's value lives: its own slot, or the caller's variable for an inout
  // parameter passed by reference.
  std::vector<Value*> refs;
  frontend::SourceSpan call_site;  // the call that created this activation
  MapContext* map = nullptr;       // the map or apply this activation serves, if any
  uint64_t activation = 0;         // numbers activations (the debugger tells them apart)
};

// An inout argument: a whole variable is passed by reference (the callee's slot points at
// it); a component or block is copied in and written back after the call.
struct Interpreter::InoutArg {
  Value* whole = nullptr;
  Place place;
  bool write_back = false;
  int slot = -1;  // the callee's parameter slot
};

// Variables are read on every other node: inline, one indirection through the frame.
inline Value& Interpreter::var(const frontend::ast::Variable& v) {
  if (v.kind == frontend::ast::Variable::Kind::Extern ||
      v.kind == frontend::ast::Variable::Kind::GlobalConst)
    return globals_[v.slot];
  return *frames_[depth_]->refs[v.slot];
}

inline Value& Interpreter::read_var(const frontend::ast::Variable& v,
                                    const frontend::ast::Expr& at) {
  Value& value = var(v);
  if (value.empty()) [[unlikely]]
    fail_unset(v, at);
  return value;
}

inline Value Interpreter::eval(const frontend::ast::Expr& e) {
  try {
    return eval_node(e);
  } catch (const runtime::Fault& f) {
    // Faults come from the operation of this very node: its operands were evaluated by
    // nested calls, which converted theirs already.
    fail(e.span, f.what());
  } catch (const std::bad_alloc&) {
    fail(e.span, "out of memory");
  }
}

// An operand by reference: a variable is read in place, anything else is computed into
// `scratch`.
inline const Value& Interpreter::operand(const frontend::ast::Expr& e, Value& scratch) {
  if (e.kind == frontend::ast::NodeKind::VarRef)
    return read_var(*static_cast<const frontend::ast::VarRef&>(e).var, e);
  scratch = eval(e);
  return scratch;
}

}  // namespace simit::interp
