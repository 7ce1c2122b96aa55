// Names, the printer and the verifier of the loop IR.
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

const char* un_name(uint8_t op) {
  static const char* const names[] = {"neg", "not", "round32", "tof64"};
  return names[op];
}
const char* bin_name(uint8_t op) {
  static const char* const names[] = {"+", "-", "*", "/", "and", "or", "xor", "mod"};
  return names[op];
}
const char* cmp_name(uint8_t op) {
  static const char* const names[] = {"==", "!=", "<", ">", "<=", ">="};
  return names[op];
}

void print_expr(std::ostream& os, const Expr& e) {
  switch (e.kind) {
    case ExprKind::Const:
      if (e.ty == Ty::F64) {
        std::ostringstream s;
        s.precision(17);
        s << e.f;
        os << s.str();
      } else if (e.ty == Ty::Bool) {
        os << (e.i ? "true" : "false");
      } else {
        os << e.i;
      }
      return;
    case ExprKind::Scalar: os << "arg" << e.slot; return;
    case ExprKind::Element: os << "e"; return;
    case ExprKind::Endpoint: os << "ep" << e.slot; return;
    case ExprKind::Load:
      os << "a" << e.slot << "[";
      print_expr(os, *e.ops[0]);
      os << "].";
      if (e.ops.size() < 2) {
        os << e.comp;
        return;
      }
      os << "(";
      if (e.comp) os << e.comp << " + ";
      print_expr(os, *e.ops[1]);
      os << ")";
      return;
    case ExprKind::Local: os << "%" << e.slot; return;
    case ExprKind::Unary:
      os << un_name(e.op) << "(";
      print_expr(os, *e.ops[0]);
      os << ")";
      return;
    case ExprKind::Binary:
    case ExprKind::Compare:
      os << "(";
      print_expr(os, *e.ops[0]);
      os << " " << (e.kind == ExprKind::Binary ? bin_name(e.op) : cmp_name(e.op)) << " ";
      print_expr(os, *e.ops[1]);
      os << ")";
      return;
    case ExprKind::Select:
      os << "select(";
      for (size_t i = 0; i < 3; ++i) {
        if (i) os << ", ";
        print_expr(os, *e.ops[i]);
      }
      os << ")";
      return;
    case ExprKind::Math:
      os << math_name(static_cast<MathFn>(e.op)) << "(";
      for (size_t i = 0; i < e.ops.size(); ++i) {
        if (i) os << ", ";
        print_expr(os, *e.ops[i]);
      }
      os << ")";
      return;
    case ExprKind::Scratch:
      os << "s" << e.slot << "[";
      print_expr(os, *e.ops[0]);
      os << "]";
      return;
  }
}

std::string line_of(const frontend::SourceSpan& s) {
  if (!s.valid()) return "";
  return "  ; line " + std::to_string(s.start().line);
}

void print_block(std::ostream& os, const std::vector<Stmt>& body, int indent) {
  const std::string pad(static_cast<size_t>(indent) * 2, ' ');
  for (const Stmt& s : body) {
    os << pad;
    switch (s.kind) {
      case StmtKind::SetLocal:
        os << "%" << s.slot << " = ";
        print_expr(os, *s.value);
        break;
      case StmtKind::Store:
        os << "a" << s.slot << "[";
        print_expr(os, *s.index);
        os << "]." << s.comp << " = ";
        print_expr(os, *s.value);
        break;
      case StmtKind::Assemble:
        os << "r" << s.slot;
        if (s.pair >= 0) {
          os << "{pair " << s.pair << "}";
        } else {
          os << "[";
          print_expr(os, *s.index);
          os << "]";
        }
        os << "." << s.comp << " <- ";
        print_expr(os, *s.value);
        break;
      case StmtKind::If:
        os << "if ";
        print_expr(os, *s.value);
        os << line_of(s.span) << "\n";
        print_block(os, s.body, indent + 1);
        if (!s.orelse.empty()) {
          os << pad << "else\n";
          print_block(os, s.orelse, indent + 1);
        }
        os << pad << "end\n";
        continue;
      case StmtKind::Check:
        os << "check ";
        print_expr(os, *s.value);
        os << " else error " << s.error;
        break;
      case StmtKind::Decompose: {
        static const char* const names[] = {"svd", "eig", "polar", "project_spd",
                                            "project_spd_abs"};
        os << "%" << s.outs.front() << "..%" << s.outs.back() << " = " << names[s.fn] << s.n << "x"
           << s.n << "(";
        for (size_t i = 0; i < s.args.size(); ++i) {
          if (i) os << ", ";
          print_expr(os, *s.args[i]);
        }
        os << ") else error " << s.error;
        break;
      }
      case StmtKind::Put:
        os << "s" << s.slot << "[";
        print_expr(os, *s.index);
        os << "] = ";
        print_expr(os, *s.value);
        break;
      case StmtKind::For:
        os << "for %" << s.slot << " < " << s.n << line_of(s.span) << "\n";
        print_block(os, s.body, indent + 1);
        os << pad << "end\n";
        continue;
    }
    os << line_of(s.span) << "\n";
  }
}

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
        if (s.pair < 0) need(s.index, Ty::I32, "assemble index");
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

void print_ops(std::ostream& os, const std::vector<VectorOp>& ops) {
  for (const VectorOp& op : ops) {
    switch (op.kind) {
      case VectorOp::Kind::Scalar: os << "    scalar"; break;
      case VectorOp::Kind::Pass: os << "    pass over n" << op.length; break;
      case VectorOp::Kind::SpMV:
        os << "    a" << op.y << " = spmv(a" << op.values << ", a" << op.x << "), blocks "
           << op.block << "x" << op.block << ", then per component";
        break;
    }
    if (op.kind != VectorOp::Kind::Scalar && !op.sums.empty()) {
      os << ", sums";
      for (int s : op.sums) os << " l" << s;
      os << " by runs of " << op.group;
    }
    if (op.guard >= 0) os << " when %" << op.guard;
    os << "\n";
    print_block(os, op.body, 3);
  }
}

}  // namespace

void print(std::ostream& os, const Trace& t) {
  os << "trace " << t.name << " (arity " << t.arity << (t.reduce ? ", reduce +" : "") << ")\n";
  for (size_t i = 0; i < t.arrays.size(); ++i) {
    const ArraySlot& a = t.arrays[i];
    static const char* const kinds[] = {"field", "vector", "result",   "table",
                                        "marks", "matrix", "positions"};
    os << "  a" << i << ": " << kinds[static_cast<int>(a.kind)] << " " << a.name << " "
       << (a.single ? "f32" : ty_name(a.ty)) << " x" << a.components
       << (a.written ? " written" : "") << "\n";
  }
  for (size_t i = 0; i < t.scalars.size(); ++i)
    os << "  arg" << i << ": " << ty_name(t.scalars[i]) << "\n";
  print_block(os, t.body, 1);
}

void print(std::ostream& os, const SystemTrace& t) {
  os << "system trace " << t.name << (t.matrices_in_place ? " (matrices read in place)" : "")
     << "\n";
  for (size_t i = 0; i < t.arrays.size(); ++i)
    os << "  a" << i << ": " << t.arrays[i].name << " "
       << (t.arrays[i].single ? "f32" : ty_name(t.arrays[i].ty))
       << (t.arrays[i].written ? " written" : "") << "\n";
  for (size_t i = 0; i < t.sizes.size(); ++i) os << "  n" << i << ": " << t.sizes[i] << "\n";
  if (!t.before.empty()) {
    os << "  before\n";
    print_ops(os, t.before);
  }
  if (t.condition) {
    os << "  while ";
    print_expr(os, *t.condition);
    os << "\n";
    print_ops(os, t.body);
  }
  if (!t.after.empty()) {
    os << "  after\n";
    print_ops(os, t.after);
  }
}

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
