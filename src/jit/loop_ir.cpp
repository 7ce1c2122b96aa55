// Names, the verifier and the node counts of the loop IR (the printer: loop_ir_print.cpp).
#include "jit/loop_ir.h"

#include <algorithm>
#include <map>
#include <sstream>

namespace simit::jit {

const char* ty_name(Ty t) {
  switch (t) {
    case Ty::F64: return "f64";
    case Ty::I32: return "i32";
    case Ty::Bool: return "bool";
  }
  return "?";
}

const char* expr_kind_name(ExprKind k) {
  switch (k) {
#define SIMIT_LOOP_NAME(n) \
  case ExprKind::n: return #n;
    SIMIT_LOOP_EXPRS(SIMIT_LOOP_NAME)
#undef SIMIT_LOOP_NAME
  }
  return "?";
}

const char* stmt_kind_name(StmtKind k) {
  switch (k) {
#define SIMIT_LOOP_NAME(n) \
  case StmtKind::n: return #n;
    SIMIT_LOOP_STMTS(SIMIT_LOOP_NAME)
#undef SIMIT_LOOP_NAME
  }
  return "?";
}

const char* math_name(MathFn f) {
  static const char* const names[] = {"sin",  "cos", "tan", "asin", "acos", "atan2", "sqrt",
                                      "cbrt", "log", "exp", "pow",  "fabs", "fmax",  "fmin"};
  return names[static_cast<int>(f)];
}

std::vector<int> decomposition_results(Decomposition d, int n) {
  const int m = n * n;
  switch (d) {
    case Decomposition::Svd: return {m, n, m};
    case Decomposition::Eig: return {n, m};
    case Decomposition::Polar: return {m, m};
    case Decomposition::ProjectSpd:
    case Decomposition::ProjectSpdAbs: return {m};
  }
  return {};
}

namespace {

// The verifier's walk: types of every operand, slots in range, and the locals set on every
// path before they are read.
class Verifier {
 public:
  // Locals 0 .. preset-1 hold values on entry (a system trace's program scalars).
  explicit Verifier(const Trace& t, int preset = 0) : t_(t), set_(t.locals.size(), false) {
    for (int i = 0; i < preset && static_cast<size_t>(i) < set_.size(); ++i) set_[i] = true;
  }

  std::string run() {
    block(t_.body);
    return error_;
  }
  // A system trace: the ops before the loop, its condition, its ops, the ops after it (t_
  // holds its arrays, locals and errors). The loop may run no iteration, so what its ops set
  // does not count as set after it.
  std::string run(const SystemTrace& st) {
    ops(st, st.before);
    if (st.condition) {
      need(st.condition, Ty::Bool, "while condition");
      const std::vector<bool> entry = set_;
      ops(st, st.body);
      set_ = entry;
    } else if (!st.body.empty()) {
      fail("loop ops without a loop condition");
    }
    ops(st, st.after);
    return error_;
  }

 private:
  // An op under a guard runs only when it holds: what it sets counts as set for the later
  // ops under the same guard, not for the others (fusion may interleave the branches).
  void ops(const SystemTrace& st, const std::vector<VectorOp>& list) {
    std::vector<bool> always = set_;
    std::map<int, std::vector<bool>> under;
    for (const VectorOp& op : list) {
      set_ = always;
      if (op.guard >= 0) {
        Expr g;
        g.kind = ExprKind::Local;
        g.ty = Ty::Bool;
        g.slot = op.guard;
        expr(g);
        if (auto it = under.find(op.guard); it != under.end())
          for (size_t i = 0; i < set_.size(); ++i) set_[i] = set_[i] || it->second[i];
      }
      if (op.kind == VectorOp::Kind::SpMV) {
        for (int a : {op.row_ptr, op.cols, op.values, op.x, op.y}) array(a, "spmv");
        if (error_.empty() && !t_.arrays[op.y].written) fail("spmv into an array not written");
      }
      if (op.kind != VectorOp::Kind::Scalar &&
          (op.length < 0 || static_cast<size_t>(op.length) >= st.sizes.size()))
        fail("a loop over a size out of range");
      for (int s : op.sums)
        if (s < 0 || static_cast<size_t>(s) >= t_.locals.size() || t_.locals[s] != Ty::F64)
          fail("a sum that is not a float local");
      block(op.body);
      (op.guard >= 0 ? under[op.guard] : always) = set_;
    }
    set_ = always;
  }

  void fail(const std::string& what) {
    if (error_.empty()) error_ = what;
  }
  void need(const ExprRef& e, Ty ty, const char* where) {
    if (!e) return fail(std::string("missing operand of ") + where);
    expr(*e);
    if (e->ty != ty)
      fail(std::string(where) + ": operand is " + ty_name(e->ty) + ", expected " + ty_name(ty));
  }
  // Whether the trace has an array of `kind` for the result that array `result_slot` is.
  bool slot_of(ArraySlot::Kind kind, int result_slot) const {
    const int result = t_.arrays[static_cast<size_t>(result_slot)].index;
    for (const ArraySlot& a : t_.arrays)
      if (a.kind == kind && a.index == result) return true;
    return false;
  }
  void array(int slot, const char* where) {
    if (slot < 0 || static_cast<size_t>(slot) >= t_.arrays.size())
      fail(std::string(where) + ": array slot " + std::to_string(slot) + " out of range");
  }
  void expr(const Expr& e) {
    switch (e.kind) {
      case ExprKind::Const:
      case ExprKind::Element: return;
      case ExprKind::Scalar:
        if (e.slot < 0 || static_cast<size_t>(e.slot) >= t_.scalars.size())
          return fail("scalar slot out of range");
        if (t_.scalars[e.slot] != e.ty) return fail("scalar read with another type");
        return;
      case ExprKind::Endpoint:
        if (e.slot < 0 || e.slot >= t_.arity) fail("endpoint out of range");
        return;
      case ExprKind::Load:
        array(e.slot, "load");
        if (error_.empty() && (e.comp < 0 || e.comp >= t_.arrays[e.slot].components))
          fail("load of component " + std::to_string(e.comp) + " out of range");
        need(e.ops.at(0), Ty::I32, "load index");
        if (e.ops.size() > 1) need(e.ops[1], Ty::I32, "load component");
        return;
      case ExprKind::Local:
        if (e.slot < 0 || static_cast<size_t>(e.slot) >= t_.locals.size())
          return fail("local out of range");
        if (!set_[e.slot]) fail("local %" + std::to_string(e.slot) + " read before it is set");
        if (t_.locals[e.slot] != e.ty) fail("local read with another type");
        return;
      case ExprKind::Unary:
        if (e.op == static_cast<uint8_t>(UnOp::Not)) return need(e.ops.at(0), Ty::Bool, "not");
        if (e.op == static_cast<uint8_t>(UnOp::ToF64)) return need(e.ops.at(0), Ty::I32, "tof64");
        return need(e.ops.at(0), e.ty, "unary");
      case ExprKind::Binary:
        need(e.ops.at(0), e.ty, "binary");
        return need(e.ops.at(1), e.ty, "binary");
      case ExprKind::Compare:
        if (e.ty != Ty::Bool) fail("comparison not of type bool");
        if (!e.ops.at(0) || !e.ops.at(1)) return fail("comparison operand missing");
        expr(*e.ops[0]);
        return need(e.ops[1], e.ops[0]->ty, "comparison");
      case ExprKind::Select:
        need(e.ops.at(0), Ty::Bool, "select condition");
        need(e.ops.at(1), e.ty, "select");
        return need(e.ops.at(2), e.ty, "select");
      case ExprKind::Math:
        for (const ExprRef& o : e.ops) need(o, Ty::F64, math_name(static_cast<MathFn>(e.op)));
        return;
      case ExprKind::Scratch:
        scratch(e.slot, "scratch read");
        if (e.ty != Ty::F64) fail("scratch read not of type f64");
        return need(e.ops.at(0), Ty::I32, "scratch index");
    }
  }
  void scratch(int slot, const char* where) {
    if (slot < 0 || static_cast<size_t>(slot) >= t_.scratch.size())
      fail(std::string(where) + ": scratch array " + std::to_string(slot) + " out of range");
  }
  void block(const std::vector<Stmt>& body) {
    for (const Stmt& s : body) stmt(s);
  }
  void stmt(const Stmt& s) {
    switch (s.kind) {
      case StmtKind::SetLocal:
        if (s.slot < 0 || static_cast<size_t>(s.slot) >= t_.locals.size())
          return fail("local out of range");
        need(s.value, t_.locals[s.slot], "set local");
        set_[s.slot] = true;
        return;
      case StmtKind::Store:
        array(s.slot, "store");
        if (!error_.empty()) return;
        if (!t_.arrays[s.slot].written) fail("store into an array not marked written");
        need(s.index, Ty::I32, "store index");
        return need(s.value, t_.arrays[s.slot].ty, "store");
      case StmtKind::Assemble:
        array(s.slot, "assemble");
        if (!error_.empty()) return;
        if (s.pair < 0 && s.member < 0) need(s.index, Ty::I32, "assemble index");
        if (s.member >= 0 && !t_.deferred) fail("assemble at a member outside a deferred trace");
        if ((s.pair >= 0 || s.member >= 0) && !slot_of(ArraySlot::Kind::Table, s.slot))
          fail("assemble through a table the trace lacks");
        if (t_.deferred && !slot_of(ArraySlot::Kind::Deferred, s.slot))
          fail("deferred assemble without deferred blocks");
        return need(s.value, t_.arrays[s.slot].ty, "assemble");
      case StmtKind::If: {
        need(s.value, Ty::Bool, "if");
        const std::vector<bool> before = set_;
        block(s.body);
        std::vector<bool> then_set = set_;
        set_ = before;
        block(s.orelse);
        for (size_t i = 0; i < set_.size(); ++i) set_[i] = set_[i] && then_set[i];
        return;
      }
      case StmtKind::Check:
        if (s.error < 0 || static_cast<size_t>(s.error) >= t_.errors.size())
          fail("check without error");
        return need(s.value, Ty::Bool, "check");
      case StmtKind::Decompose: {
        if (s.error < 0 || static_cast<size_t>(s.error) >= t_.errors.size())
          fail("decomposition without error");
        if (s.args.size() != static_cast<size_t>(s.n) * s.n)
          return fail("decomposition argument count");
        for (const ExprRef& a : s.args) need(a, Ty::F64, "decomposition");
        size_t outs = 0;
        for (int c : decomposition_results(static_cast<Decomposition>(s.fn), s.n))
          outs += static_cast<size_t>(c);
        if (s.outs.size() != outs) return fail("decomposition result count");
        for (int l : s.outs) {
          if (l < 0 || static_cast<size_t>(l) >= t_.locals.size() || t_.locals[l] != Ty::F64)
            return fail("decomposition result local");
          set_[l] = true;
        }
        return;
      }
      case StmtKind::Put:
        scratch(s.slot, "put");
        need(s.index, Ty::I32, "put index");
        return need(s.value, Ty::F64, "put");
      case StmtKind::For: {
        if (s.slot < 0 || static_cast<size_t>(s.slot) >= t_.locals.size() ||
            t_.locals[s.slot] != Ty::I32)
          return fail("for over a local that is not an i32");
        if (s.n < 0) return fail("for with a negative trip count");
        // What the body sets counts only inside it: its values are per iteration.
        const std::vector<bool> before = set_;
        set_[s.slot] = true;
        block(s.body);
        set_ = before;
        return;
      }
    }
  }

  const Trace& t_;
  std::vector<bool> set_;
  std::string error_;
};

size_t count_expr(const Expr& e) {
  size_t n = 1;
  for (const ExprRef& o : e.ops) n += count_expr(*o);
  return n;
}

size_t count_block(const std::vector<Stmt>& body) {
  size_t n = 0;
  for (const Stmt& s : body) {
    n += 1 + (s.value ? count_expr(*s.value) : 0) + (s.index ? count_expr(*s.index) : 0);
    for (const ExprRef& a : s.args) n += count_expr(*a);
    n += count_block(s.body) + count_block(s.orelse);
  }
  return n;
}

}  // namespace

std::string verify(const Trace& t) { return Verifier(t).run(); }

std::string verify(const SystemTrace& st) {
  Trace t;
  t.arrays = st.arrays;
  t.locals = st.locals;
  t.errors = st.errors;
  return Verifier(t, st.scalars).run(st);
}

size_t node_count(const Trace& t) { return count_block(t.body); }

size_t node_count(const SystemTrace& t) {
  size_t n = t.condition ? count_expr(*t.condition) : 0;
  for (const auto* ops : {&t.before, &t.body, &t.after})
    for (const VectorOp& op : *ops) n += 1 + count_block(op.body);
  return n;
}

}  // namespace simit::jit
