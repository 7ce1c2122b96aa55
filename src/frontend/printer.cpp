// print_source: the AST as Simit text that parses back to the same tree. Operands are
// parenthesised generously; only the bracketing the grammar itself needs is omitted.
#include "frontend/printer.h"

#include <charconv>
#include <cmath>
#include <set>

namespace simit::frontend {
namespace {

using namespace ast;

// How tightly a printed expression binds (§6.1), for deciding on parentheses.
enum Level { kLow, kTranspose, kRead, kField, kSetRead, kFactor };

std::string format_float(double v) {
  char buf[64];
  auto result = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, result.ptr);
  // The lexer needs a '.' or an exponent to see a float.
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

std::string format_complex(std::complex<double> c) {
  return "<" + format_float(c.real()) + ", " + format_float(c.imag()) + ">";
}

std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      case '\a': out += "\\a"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      case '\v': out += "\\v"; break;
      default: out += c;
    }
  }
  return out + "\"";
}

std::string verbatim(const SourceSpan& span) {
  if (!span.valid()) return "";
  return span.file->text().substr(span.begin, span.end - span.begin);
}

std::string index_set(const IndexSetExpr& e) { return e.is_int ? std::to_string(e.value) : e.name; }

std::string index_set_list(const std::vector<IndexSetExpr>& list) {
  std::string out;
  for (size_t i = 0; i < list.size(); ++i) out += (i ? ", " : "") + index_set(list[i]);
  return out;
}

// One entry of a flattened dense literal.
std::string dense_entry(const DenseLit& d, size_t i) {
  switch (d.component) {
    case ScalarKind::Int: return i < d.ints.size() ? std::to_string(d.ints[i]) : "0";
    case ScalarKind::Complex:
      return i < d.complexes.size() ? format_complex(d.complexes[i]) : "<0.0, 0.0>";
    default: return i < d.floats.size() ? format_float(d.floats[i]) : "0.0";
  }
}

// Dimensions from `dim` on, entries from `first`: nested brackets for order >= 2, so the
// text has exactly this shape when parsed again.
std::string dense_body(const DenseLit& d, size_t dim, size_t& next) {
  std::string out = "[";
  int n = d.shape[dim];
  for (int i = 0; i < n; ++i) {
    if (i) out += ", ";
    out += dim + 1 == d.shape.size() ? dense_entry(d, next++) : dense_body(d, dim + 1, next);
  }
  return out + "]";
}

std::string type_text(const TypeExpr& t);

std::string tensor_type_text(const TensorTypeExpr& t) {
  static const char* spellings[] = {"tensor", "vector", "matrix"};
  std::string out = spellings[static_cast<int>(t.spelling)];
  if (!t.dims.empty()) out += "[" + index_set_list(t.dims) + "]";
  out += "(" + (t.block ? type_text(*t.block) : std::string("float")) + ")";
  return out + (t.transposed ? "'" : "");
}

std::string set_type_text(const SetTypeExpr& t) {
  std::string out = "set{" + t.element + "}";
  if (t.shorthand) {
    // An arity below 1 keeps no endpoint name to print; the text itself does.
    if (t.endpoints.empty()) return verbatim(t.span);
    return out + "(" + t.endpoints[0].name + " * " + std::to_string(t.shorthand_count) + ")";
  }
  if (!t.endpoints.empty()) out += "(" + index_set_list(t.endpoints) + ")";
  return out;
}

std::string tuple_type_text(const TupleTypeExpr& t) {
  if (!t.named)
    return "(" + (t.elements.empty() ? "" : t.elements[0]) + " * " + std::to_string(t.count) + ")";
  std::string out = "(";
  for (size_t i = 0; i < t.elements.size(); ++i)
    out += (i ? ", " : "") + t.names[i] + " : " + t.elements[i];
  return out + ")";
}

std::string type_text(const TypeExpr& t) {
  switch (t.kind) {
    case NodeKind::ScalarTypeExpr: return to_string(t.as<ScalarTypeExpr>()->scalar);
    case NodeKind::TensorTypeExpr: return tensor_type_text(*t.as<TensorTypeExpr>());
    case NodeKind::NamedTypeExpr: return t.as<NamedTypeExpr>()->name;
    case NodeKind::SetTypeExpr: return set_type_text(*t.as<SetTypeExpr>());
    case NodeKind::GridTypeExpr: {
      const auto* g = t.as<GridTypeExpr>();
      return "grid[" + std::to_string(g->dims) + "]{" + g->element + "}(" + g->point_set.name + ")";
    }
    case NodeKind::TupleTypeExpr: return tuple_type_text(*t.as<TupleTypeExpr>());
    case NodeKind::OpaqueTypeExpr: return "opaque";
    default: return "?";
  }
}

class SourcePrinter {
 public:
  std::string program(const Program& p) {
    for (const auto& d : p.decls) decl(*d);
    return std::move(out_);
  }

 private:
  void line(const std::string& text) {
    out_.append(static_cast<size_t>(indent_) * 2, ' ');
    out_ += text;
    out_ += '\n';
  }

  // ---- expressions

  static Level level(const Expr& e) {
    switch (e.kind) {
      case NodeKind::IntLit: return e.as<IntLit>()->value < 0 ? kLow : kFactor;
      case NodeKind::FloatLit: return std::signbit(e.as<FloatLit>()->value) ? kLow : kFactor;
      case NodeKind::DenseLit: {
        const auto* d = e.as<DenseLit>();
        if (!d->shape_error.empty()) return kLow;
        return d->column ? kTranspose : kFactor;
      }
      case NodeKind::BoolLit:
      case NodeKind::StringLit:
      case NodeKind::ComplexLit:
      case NodeKind::VarRef:
      case NodeKind::Call:
      case NodeKind::TupleRead: return kFactor;
      case NodeKind::SetRead: return kSetRead;
      case NodeKind::FieldRead: return kField;
      case NodeKind::TensorRead: return kRead;
      case NodeKind::Transpose: return kTranspose;
      default: return kLow;
    }
  }

  // `e` where the grammar needs at least `min`.
  std::string operand(const Expr& e, Level min = kTranspose) {
    std::string text = expr(e);
    return level(e) >= min ? text : "(" + text + ")";
  }

  // The base of `(...)` or `.f`: a tuple parameter's bare name there would read as a
  // tuple read (§3.6.1), so it is bracketed.
  std::string read_base(const Expr& base, Level min) {
    if (const auto* ref = base.as<VarRef>(); ref && tuple_names_.count(ref->name))
      return "(" + ref->name + ")";
    return operand(base, min);
  }

  std::string list(const std::vector<ExprPtr>& items) {
    std::string out;
    for (size_t i = 0; i < items.size(); ++i)
      out += (i ? ", " : "") + (items[i] ? operand(*items[i]) : std::string(":"));
    return out;
  }

  std::string dense(const DenseLit& d) {
    if (!d.shape_error.empty() || d.shape.empty()) return verbatim(d.span);
    size_t next = 0;
    return dense_body(d, 0, next) + (d.column ? "'" : "");
  }

  std::string assembly(const Assembly& a) {
    std::string out = a.func;
    if (!a.generic_args.empty()) out += "<" + index_set_list(a.generic_args) + ">";
    if (!a.args.empty()) out += "(" + list(a.args) + ")";
    return out + " to " + a.target;
  }

  std::string binary(const Binary& b) {
    return operand(*b.lhs) + " " + binary_op_spelling(b.op) + " " + operand(*b.rhs);
  }

  std::string compare(const Compare& c) {
    std::string out = operand(*c.operands[0]);
    for (size_t i = 0; i < c.ops.size(); ++i)
      out += std::string(" ") + compare_op_spelling(c.ops[i]) + " " + operand(*c.operands[i + 1]);
    return out;
  }

  std::string unary(const Unary& u) {
    const char* op = u.op == Unary::Op::Not ? "not " : u.op == Unary::Op::Neg ? "-" : "+";
    // Prefix operators nest without brackets (`- -x`, `not not b`); brackets would double
    // the nesting depth of the printed text and could push it past the parser's limit.
    if (const auto* inner = u.operand->as<Unary>();
        inner && (u.op == Unary::Op::Not || inner->op != Unary::Op::Not))
      return std::string(op) + (u.op == Unary::Op::Not ? "" : " ") + unary(*inner);
    return op + operand(*u.operand);
  }

  std::string map(const Map& m) {
    std::string out = "map " + assembly(m.assembly);
    if (!m.through.empty()) out += " through " + m.through;
    return out + (m.reduce ? " reduce +" : "");
  }

  std::string set_read(const SetRead& s) {
    std::string out = operand(*s.base, kFactor) + "[" + list(s.first);
    if (s.has_semicolon) out += "; " + list(s.second);
    return out + "]";
  }

  std::string tuple_read(const TupleRead& t) {
    std::string base = operand(*t.base, kFactor);
    if (t.index) return base + "(" + expr(*t.index) + ")";
    return base + "." + t.member;
  }

  std::string call(const Call& c) {
    std::string out = c.callee;
    if (!c.generic_args.empty()) out += "<" + index_set_list(c.generic_args) + ">";
    return out + "(" + list(c.args) + ")";
  }

  std::string expr(const Expr& e) {
    switch (e.kind) {
      case NodeKind::IntLit: return std::to_string(e.as<IntLit>()->value);
      case NodeKind::FloatLit: return format_float(e.as<FloatLit>()->value);
      case NodeKind::BoolLit: return e.as<BoolLit>()->value ? "true" : "false";
      case NodeKind::StringLit: return quote(e.as<StringLit>()->value);
      case NodeKind::ComplexLit: return format_complex(e.as<ComplexLit>()->value);
      case NodeKind::DenseLit: return dense(*e.as<DenseLit>());
      case NodeKind::VarRef: return e.as<VarRef>()->name;
      case NodeKind::Call: return call(*e.as<Call>());
      case NodeKind::TensorRead: {
        const auto* r = e.as<TensorRead>();
        return read_base(*r->base, kRead) + "(" + list(r->indices) + ")";
      }
      case NodeKind::TupleRead: return tuple_read(*e.as<TupleRead>());
      case NodeKind::FieldRead: {
        const auto* f = e.as<FieldRead>();
        // `0.k` would lex as the malformed number `0.`; the checker rejects such a read, but
        // the printed text must still parse.
        if (f->base->is<IntLit>()) return "(" + expr(*f->base) + ")." + f->field;
        return read_base(*f->base, kSetRead) + "." + f->field;
      }
      case NodeKind::SetRead: return set_read(*e.as<SetRead>());
      case NodeKind::Unary: return unary(*e.as<Unary>());
      case NodeKind::Binary: return binary(*e.as<Binary>());
      case NodeKind::Compare: return compare(*e.as<Compare>());
      case NodeKind::Transpose: return operand(*e.as<Transpose>()->operand) + "'";
      case NodeKind::Map: return map(*e.as<Map>());
      default: return "?";
    }
  }

  // ---- statements

  // A block whose first statement starts with a token that could continue the
  // preceding condition or bound gets an empty statement in between.
  void block(const Block& stmts) {
    ++indent_;
    size_t mark = out_.size();
    for (const auto& s : stmts) stmt(*s);
    if (out_.size() > mark) {
      size_t first = out_.find_first_not_of(' ', mark);
      if (first != std::string::npos &&
          std::string("([<-+'.").find(out_[first]) != std::string::npos)
        out_.insert(mark, std::string(static_cast<size_t>(indent_) * 2, ' ') + ";\n");
    }
    --indent_;
  }

  std::string var_decl(const VarDecl& d) {
    std::string out = (d.is_const ? "const " : "var ") + d.name;
    if (d.declared) out += " : " + type_text(*d.declared);
    if (d.init) out += " = " + expr(*d.init);
    return out + ";";
  }

  void if_stmt(const If& s) {
    for (size_t i = 0; i < s.conditions.size(); ++i) {
      line((i ? "elif " : "if ") + expr(*s.conditions[i]));
      block(s.branches[i]);
    }
    if (s.has_else) {
      line("else");
      block(s.else_branch);
    }
    line("end");
  }

  std::string for_bound(const Expr& e) {
    std::string text = expr(e);
    return e.is<VarRef>() || (e.is<IntLit>() && level(e) == kFactor) ? text : "(" + text + ")";
  }

  void stmt(const Stmt& s) {
    switch (s.kind) {
      case NodeKind::VarDecl: return line(var_decl(*s.as<VarDecl>()));
      case NodeKind::IvarDecl: return line("ivar " + s.as<IvarDecl>()->name + ";");
      case NodeKind::Assign: {
        const auto* a = s.as<Assign>();
        return line(list(a->targets) + " = " + expr(*a->value) + ";");
      }
      case NodeKind::ExprStmt: return line(expr(*s.as<ExprStmt>()->expr) + ";");
      case NodeKind::If: return if_stmt(*s.as<If>());
      case NodeKind::While: {
        const auto* w = s.as<While>();
        line("while " + expr(*w->condition));
        block(w->body);
        return line("end");
      }
      case NodeKind::DoWhile: {
        const auto* d = s.as<DoWhile>();
        line("do");
        block(d->body);
        return line("end while " + expr(*d->condition) + ";");
      }
      case NodeKind::ForRange: {
        const auto* f = s.as<ForRange>();
        line("for " + f->var_name + " in " + for_bound(*f->lo) + " : " + for_bound(*f->hi));
        block(f->body);
        return line("end");
      }
      case NodeKind::ForSet: {
        const auto* f = s.as<ForSet>();
        line("for " + f->var_name + " in " + f->domain);
        block(f->body);
        return line("end");
      }
      case NodeKind::Print: {
        const auto* p = s.as<Print>();
        static const char* const keywords[] = {"print ", "println ", "error "};
        return line(keywords[static_cast<int>(p->mode)] + list(p->args) + ";");
      }
      case NodeKind::Apply: return line("apply " + assembly(s.as<Apply>()->assembly) + ";");
      default: return line("?;");
    }
  }

  // ---- program elements

  std::string params(const std::vector<Param>& ps, bool with_inout) {
    std::string out;
    for (size_t i = 0; i < ps.size(); ++i) {
      out += i ? ", " : "";
      if (with_inout && ps[i].inout) out += "inout ";
      out += ps[i].name + " : " + (ps[i].type_expr ? type_text(*ps[i].type_expr) : "?");
    }
    return out;
  }

  std::string func_header(const FuncDecl& f) {
    std::string out = f.exported ? "export func " : f.is_extern ? "extern func " : "func ";
    out += f.name;
    if (!f.generics.empty()) {
      out += "<";
      for (size_t i = 0; i < f.generics.size(); ++i)
        out += (i ? ", " : "") + std::string(f.generics[i].ranged ? "0:" : "") + f.generics[i].name;
      out += ">";
    }
    out += "(" + params(f.params, true) + ")";
    if (!f.results.empty()) out += " -> (" + params(f.results, false) + ")";
    return out;
  }

  void func(const FuncDecl& f) {
    tuple_names_.clear();
    for (const auto* ps : {&f.params, &f.results})
      for (const auto& p : *ps)
        if (p.type_expr && p.type_expr->is<TupleTypeExpr>()) tuple_names_.insert(p.name);
    if (f.is_extern) return line(func_header(f) + ";");
    line(func_header(f));
    block(f.body);
    line("end");
    tuple_names_.clear();
  }

  void decl(const Decl& d) {
    switch (d.kind) {
      case NodeKind::ElementDecl: {
        const auto* e = d.as<ElementDecl>();
        line("element " + e->name);
        ++indent_;
        for (const auto& f : e->fields)
          line(f.name + " : " + (f.type_expr ? type_text(*f.type_expr) : "?") + ";");
        --indent_;
        return line("end");
      }
      case NodeKind::ExternDecl: {
        const auto* e = d.as<ExternDecl>();
        return line("extern " + e->name + " : " + type_text(*e->type_expr) + ";");
      }
      case NodeKind::ConstDecl: return line(var_decl(*d.as<ConstDecl>()->decl));
      case NodeKind::FuncDecl: return func(*d.as<FuncDecl>());
      case NodeKind::TestDecl: {
        const auto* t = d.as<TestDecl>();
        return line("%! " + t->func + "(" + list(t->args) + ") == " + operand(*t->expected) + ";");
      }
      default: return line("% ?");
    }
  }

  std::string out_;
  int indent_ = 0;
  std::set<std::string> tuple_names_;  // tuple parameters and results of the function
};

}  // namespace

std::string print_source(const ast::Program& program) { return SourcePrinter().program(program); }

}  // namespace simit::frontend
