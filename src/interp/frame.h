// The interpreter's activation records: one slot per variable of a function (the checker
// numbers them), and the bookkeeping of inout arguments of pending calls.
#pragma once

#include <vector>

#include "frontend/ast.h"
#include "interp/interpreter.h"

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

inline Value& Interpreter::read_var(const frontend::ast::Variable& v, const frontend::ast::Expr& at) {
  Value& value = var(v);
  if (value.empty()) [[unlikely]]
    fail_unset(v, at);
  return value;
}

}  // namespace simit::interp
