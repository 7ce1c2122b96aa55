// The loop IR's printer (`--dump=loop-ir,passes`): one function per node kind, dispatched
// from the node lists (SIMIT_LOOP_EXPRS, SIMIT_LOOP_STMTS), so that a kind added to a list
// without its printer does not compile.
#include <sstream>
#include <string>

#include "jit/loop_ir.h"

namespace simit::jit {

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

void print_expr(std::ostream& os, const Expr& e);

void print_node_Const(std::ostream& os, const Expr& e) {
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
}

void print_node_Scalar(std::ostream& os, const Expr& e) { os << "arg" << e.slot; }

void print_node_Element(std::ostream& os, const Expr&) { os << "e"; }

void print_node_Endpoint(std::ostream& os, const Expr& e) { os << "ep" << e.slot; }

void print_node_Load(std::ostream& os, const Expr& e) {
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
}

void print_node_Local(std::ostream& os, const Expr& e) { os << "%" << e.slot; }

void print_node_Unary(std::ostream& os, const Expr& e) {
  os << un_name(e.op) << "(";
  print_expr(os, *e.ops[0]);
  os << ")";
}

// Binary and Compare: an infix operator.
void print_node_Binary(std::ostream& os, const Expr& e) {
  os << "(";
  print_expr(os, *e.ops[0]);
  os << " " << (e.kind == ExprKind::Binary ? bin_name(e.op) : cmp_name(e.op)) << " ";
  print_expr(os, *e.ops[1]);
  os << ")";
}

void print_node_Select(std::ostream& os, const Expr& e) {
  os << "select(";
  for (size_t i = 0; i < 3; ++i) {
    if (i) os << ", ";
    print_expr(os, *e.ops[i]);
  }
  os << ")";
}

void print_node_Math(std::ostream& os, const Expr& e) {
  os << math_name(static_cast<MathFn>(e.op)) << "(";
  for (size_t i = 0; i < e.ops.size(); ++i) {
    if (i) os << ", ";
    print_expr(os, *e.ops[i]);
  }
  os << ")";
}

void print_node_Scratch(std::ostream& os, const Expr& e) {
  os << "s" << e.slot << "[";
  print_expr(os, *e.ops[0]);
  os << "]";
}

void print_node_Compare(std::ostream& os, const Expr& e) { print_node_Binary(os, e); }

void print_expr(std::ostream& os, const Expr& e) {
  switch (e.kind) {
#define SIMIT_LOOP_PRINT(n) \
  case ExprKind::n: return print_node_##n(os, e);
    SIMIT_LOOP_EXPRS(SIMIT_LOOP_PRINT)
#undef SIMIT_LOOP_PRINT
  }
}

std::string line_of(const frontend::SourceSpan& s) {
  if (!s.valid()) return "";
  return "  ; line " + std::to_string(s.start().line);
}

void print_block(std::ostream& os, const std::vector<Stmt>& body, int indent);

// A statement's printer writes it after the indentation `pad`; it returns whether the
// statement ends on its line (the caller adds the source line), or printed its own ending
// (a block: its body and `end`).
using Pad = const std::string&;

bool print_node_SetLocal(std::ostream& os, const Stmt& s, Pad, int) {
  os << "%" << s.slot << " = ";
  print_expr(os, *s.value);
  return true;
}

bool print_node_Store(std::ostream& os, const Stmt& s, Pad, int) {
  os << "a" << s.slot << "[";
  print_expr(os, *s.index);
  os << "]." << s.comp << " = ";
  print_expr(os, *s.value);
  return true;
}

bool print_node_Assemble(std::ostream& os, const Stmt& s, Pad, int) {
  os << "r" << s.slot;
  if (s.pair >= 0) {
    os << "{pair " << s.pair << "}";
  } else if (s.member >= 0) {
    os << "{member " << s.member << "}";
  } else {
    os << "[";
    print_expr(os, *s.index);
    os << "]";
  }
  os << "." << s.comp << " <- ";
  print_expr(os, *s.value);
  return true;
}

bool print_node_If(std::ostream& os, const Stmt& s, Pad pad, int indent) {
  os << "if ";
  print_expr(os, *s.value);
  os << line_of(s.span) << "\n";
  print_block(os, s.body, indent + 1);
  if (!s.orelse.empty()) {
    os << pad << "else\n";
    print_block(os, s.orelse, indent + 1);
  }
  os << pad << "end\n";
  return false;
}

bool print_node_Check(std::ostream& os, const Stmt& s, Pad, int) {
  os << "check ";
  print_expr(os, *s.value);
  os << " else error " << s.error;
  return true;
}

bool print_node_Decompose(std::ostream& os, const Stmt& s, Pad, int) {
  static const char* const names[] = {"svd", "eig", "polar", "project_spd", "project_spd_abs"};
  os << "%" << s.outs.front() << "..%" << s.outs.back() << " = " << names[s.fn] << s.n << "x" << s.n
     << "(";
  for (size_t i = 0; i < s.args.size(); ++i) {
    if (i) os << ", ";
    print_expr(os, *s.args[i]);
  }
  os << ") else error " << s.error;
  return true;
}

bool print_node_Put(std::ostream& os, const Stmt& s, Pad, int) {
  os << "s" << s.slot << "[";
  print_expr(os, *s.index);
  os << "] = ";
  print_expr(os, *s.value);
  return true;
}

bool print_node_For(std::ostream& os, const Stmt& s, Pad pad, int indent) {
  os << "for %" << s.slot << " < " << s.n << line_of(s.span) << "\n";
  print_block(os, s.body, indent + 1);
  os << pad << "end\n";
  return false;
}

bool print_stmt(std::ostream& os, const Stmt& s, Pad pad, int indent) {
  switch (s.kind) {
#define SIMIT_LOOP_PRINT(n) \
  case StmtKind::n: return print_node_##n(os, s, pad, indent);
    SIMIT_LOOP_STMTS(SIMIT_LOOP_PRINT)
#undef SIMIT_LOOP_PRINT
  }
  return true;
}

void print_block(std::ostream& os, const std::vector<Stmt>& body, int indent) {
  const std::string pad(static_cast<size_t>(indent) * 2, ' ');
  for (const Stmt& s : body) {
    os << pad;
    if (print_stmt(os, s, pad, indent)) os << line_of(s.span) << "\n";
  }
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
  os << "trace " << t.name << " (arity " << t.arity << (t.reduce ? ", reduce +" : "")
     << (t.deferred ? ", deferred" : "") << ")\n";
  for (size_t i = 0; i < t.arrays.size(); ++i) {
    const ArraySlot& a = t.arrays[i];
    static const char* const kinds[] = {"field", "vector", "result",    "table",
                                        "marks", "matrix", "positions", "deferred"};
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
     << (t.device ? " (device program)" : "") << (t.float32 ? " (binary32 sums)" : "") << "\n";
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

}  // namespace simit::jit
