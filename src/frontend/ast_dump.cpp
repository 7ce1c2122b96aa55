// dump_ast and dump_typed: one node per line, indented, with its key attributes and
// `@line:col`; the typed dump adds the checker's annotations where they are present.
#include <charconv>
#include <sstream>

#include "frontend/printer.h"

namespace simit::frontend {
namespace {

using namespace ast;

const char* variable_kind_name(Variable::Kind k) {
  switch (k) {
    case Variable::Kind::Extern: return "extern";
    case Variable::Kind::GlobalConst: return "global-const";
    case Variable::Kind::Param: return "param";
    case Variable::Kind::Result: return "result";
    case Variable::Kind::Local: return "local";
    case Variable::Kind::Implicit: return "implicit";
    case Variable::Kind::LoopVar: return "loop-var";
    case Variable::Kind::IndexVar: return "index-var";
    case Variable::Kind::Generic: return "generic";
  }
  return "?";
}

std::string num(double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string complex_text(std::complex<double> c) {
  return "<" + num(c.real()) + "," + num(c.imag()) + ">";
}

std::string index_sets(const std::vector<IndexSetExpr>& list) {
  std::string out;
  for (size_t i = 0; i < list.size(); ++i)
    out += (i ? "," : "") + (list[i].is_int ? std::to_string(list[i].value) : list[i].name);
  return out;
}

std::string dense_values(const DenseLit& d) {
  constexpr size_t kShown = 16;  // long literals are abbreviated
  std::string out = "{";
  size_t n = d.ints.size() + d.floats.size() + d.complexes.size();
  for (size_t i = 0; i < n && i < kShown; ++i) {
    out += i ? ", " : "";
    if (i < d.ints.size())
      out += std::to_string(d.ints[i]);
    else if (i < d.ints.size() + d.floats.size())
      out += num(d.floats[i - d.ints.size()]);
    else
      out += complex_text(d.complexes[i - d.ints.size() - d.floats.size()]);
  }
  return out + (n > kShown ? ", ...}" : "}");
}

class Dumper {
 public:
  explicit Dumper(bool typed) : typed_(typed) {}

  std::string program(const Program& p) {
    for (const auto& d : p.decls) decl(*d);
    return out_.str();
  }

 private:
  // One line: indentation, text, location.
  void line(const std::string& text, const SourceSpan& span) {
    out_ << std::string(static_cast<size_t>(depth_) * 2, ' ') << text;
    if (span.valid()) {
      LineCol lc = span.start();
      out_ << " @" << lc.line << ":" << lc.column;
    }
    out_ << "\n";
  }
  void label(const std::string& text) {
    out_ << std::string(static_cast<size_t>(depth_) * 2, ' ') << text << "\n";
  }

  std::string var_note(const Variable* v) const {
    if (!typed_ || !v) return "";
    std::string out = std::string(" -> ") + variable_kind_name(v->kind) + " '" + v->name + "'";
    if (v->slot >= 0) out += " slot " + std::to_string(v->slot);
    if (v->type) out += " : " + to_string(*v->type);
    return out;
  }
  std::string type_note(const TypeRef& t) const { return typed_ && t ? " : " + to_string(*t) : ""; }

  struct Nest {
    explicit Nest(Dumper& d) : d_(d) { ++d_.depth_; }
    ~Nest() { --d_.depth_; }
    Dumper& d_;
  };

  // ---- types

  std::string type_attrs(const TypeExpr& t) {
    switch (t.kind) {
      case NodeKind::ScalarTypeExpr: return " " + to_string(t.as<ScalarTypeExpr>()->scalar);
      case NodeKind::TensorTypeExpr: {
        const auto* x = t.as<TensorTypeExpr>();
        static const char* spellings[] = {"tensor", "vector", "matrix"};
        std::string out = std::string(" ") + spellings[static_cast<int>(x->spelling)];
        if (!x->dims.empty()) out += "[" + index_sets(x->dims) + "]";
        return out + (x->transposed ? "'" : "");
      }
      case NodeKind::NamedTypeExpr: return " " + t.as<NamedTypeExpr>()->name;
      case NodeKind::SetTypeExpr: {
        const auto* s = t.as<SetTypeExpr>();
        std::string out = " {" + s->element + "}";
        if (!s->endpoints.empty()) out += "(" + index_sets(s->endpoints) + ")";
        if (s->shorthand) out += " shorthand*" + std::to_string(s->shorthand_count);
        return out;
      }
      case NodeKind::GridTypeExpr: {
        const auto* g = t.as<GridTypeExpr>();
        return " [" + std::to_string(g->dims) + "]{" + g->element + "}(" + g->point_set.name + ")";
      }
      case NodeKind::TupleTypeExpr: {
        const auto* x = t.as<TupleTypeExpr>();
        if (!x->named)
          return " (" + (x->elements.empty() ? "" : x->elements[0]) + "*" +
                 std::to_string(x->count) + ")";
        std::string out = " (";
        for (size_t i = 0; i < x->elements.size(); ++i)
          out += (i ? ", " : "") + x->names[i] + ":" + x->elements[i];
        return out + ")";
      }
      default: return "";
    }
  }

  void type(const TypeExpr& t) {
    line(std::string(node_kind_name(t.kind)) + type_attrs(t) + type_note(t.type), t.span);
    if (const auto* x = t.as<TensorTypeExpr>(); x && x->block) {
      Nest n(*this);
      type(*x->block);
    }
  }

  // ---- expressions

  std::string expr_attrs(const Expr& e) {
    switch (e.kind) {
      case NodeKind::IntLit: return " " + std::to_string(e.as<IntLit>()->value);
      case NodeKind::FloatLit: return " " + num(e.as<FloatLit>()->value);
      case NodeKind::BoolLit: return e.as<BoolLit>()->value ? " true" : " false";
      case NodeKind::StringLit: return " \"" + e.as<StringLit>()->value + "\"";
      case NodeKind::ComplexLit: return " " + complex_text(e.as<ComplexLit>()->value);
      case NodeKind::DenseLit: return dense_attrs(*e.as<DenseLit>());
      case NodeKind::VarRef: return " " + e.as<VarRef>()->name + var_note(e.as<VarRef>()->var);
      case NodeKind::Call: return call_attrs(*e.as<Call>());
      case NodeKind::TensorRead:
        return typed_ && e.as<TensorRead>()->index_notation ? " index-notation" : "";
      case NodeKind::TupleRead: {
        const auto* t = e.as<TupleRead>();
        return t->index ? "" : " ." + t->member;
      }
      case NodeKind::FieldRead: {
        const auto* f = e.as<FieldRead>();
        std::string out = " ." + f->field;
        if (typed_ && f->field_index >= 0) out += " #" + std::to_string(f->field_index);
        return out + (typed_ && f->of_set ? " of-set" : "");
      }
      case NodeKind::SetRead: return e.as<SetRead>()->has_semicolon ? " with-semicolon" : "";
      case NodeKind::Unary: {
        auto op = e.as<Unary>()->op;
        return op == Unary::Op::Not ? " not" : op == Unary::Op::Neg ? " -" : " +";
      }
      case NodeKind::Binary: return std::string(" ") + binary_op_spelling(e.as<Binary>()->op);
      case NodeKind::Compare: {
        std::string out;
        for (auto op : e.as<Compare>()->ops) out += std::string(" ") + compare_op_spelling(op);
        return out;
      }
      case NodeKind::Map: return map_attrs(*e.as<Map>());
      default: return "";
    }
  }

  std::string dense_attrs(const DenseLit& d) {
    std::string out = " " + to_string(d.component) + " [";
    for (size_t i = 0; i < d.shape.size(); ++i) out += (i ? "," : "") + std::to_string(d.shape[i]);
    out += "]";
    if (d.column) out += " column";
    if (!d.shape_error.empty()) out += " error='" + d.shape_error + "'";
    return out + " " + dense_values(d);
  }

  std::string call_attrs(const Call& c) {
    std::string out = " " + c.callee;
    if (!c.generic_args.empty()) out += "<" + index_sets(c.generic_args) + ">";
    if (typed_ && c.func) out += " -> func '" + c.func->name + "'";
    if (typed_ && c.intrinsic != Intrinsic::None)
      out += std::string(" -> intrinsic '") + intrinsic_name(c.intrinsic) + "'";
    return out;
  }

  std::string assembly_attrs(const Assembly& a) {
    std::string out = " " + a.func;
    if (!a.generic_args.empty()) out += "<" + index_sets(a.generic_args) + ">";
    out += " to " + a.target;
    if (typed_ && a.callee) out += " -> func '" + a.callee->name + "'";
    if (typed_ && a.pass_endpoints) out += " endpoints";
    return out;
  }

  std::string map_attrs(const Map& m) {
    std::string out = assembly_attrs(m.assembly);
    if (!m.through.empty()) out += " through " + m.through;
    return out + (m.reduce ? " reduce +" : "");
  }

  void expr(const Expr& e) {
    std::string text = std::string(node_kind_name(e.kind)) + expr_attrs(e) + type_note(e.type);
    if (typed_ && e.writable) text += " writable";
    line(text, e.span);
    Nest n(*this);
    expr_children(e);
  }

  void exprs(const std::vector<ExprPtr>& list) {
    for (const auto& e : list) {
      if (e)
        expr(*e);
      else
        label("Slice :");
    }
  }

  void expr_children(const Expr& e) {
    switch (e.kind) {
      case NodeKind::Call: return exprs(e.as<Call>()->args);
      case NodeKind::TensorRead:
        expr(*e.as<TensorRead>()->base);
        return exprs(e.as<TensorRead>()->indices);
      case NodeKind::TupleRead:
        expr(*e.as<TupleRead>()->base);
        if (e.as<TupleRead>()->index) expr(*e.as<TupleRead>()->index);
        return;
      case NodeKind::FieldRead: return expr(*e.as<FieldRead>()->base);
      case NodeKind::SetRead: {
        const auto* s = e.as<SetRead>();
        expr(*s->base);
        exprs(s->first);
        if (s->has_semicolon) label(";");
        return exprs(s->second);
      }
      case NodeKind::Unary: return expr(*e.as<Unary>()->operand);
      case NodeKind::Binary: expr(*e.as<Binary>()->lhs); return expr(*e.as<Binary>()->rhs);
      case NodeKind::Compare: return exprs(e.as<Compare>()->operands);
      case NodeKind::Transpose: return expr(*e.as<Transpose>()->operand);
      case NodeKind::Map: return exprs(e.as<Map>()->assembly.args);
      default: return;
    }
  }

  // ---- statements

  void block(const char* name, const Block& stmts) {
    label(name);
    Nest n(*this);
    for (const auto& s : stmts) stmt(*s);
  }

  void var_decl(const VarDecl& d) {
    std::string text = std::string("VarDecl ") + (d.is_const ? "const " : "var ") + d.name;
    line(text + var_note(d.var), d.span);
    Nest n(*this);
    if (d.declared) type(*d.declared);
    if (d.init) expr(*d.init);
  }

  void assign(const Assign& a) {
    std::string text = "Assign targets=" + std::to_string(a.targets.size());
    if (typed_ && a.index_notation) text += " index-notation";
    line(text, a.span);
    Nest n(*this);
    for (size_t i = 0; i < a.targets.size(); ++i) {
      expr(*a.targets[i]);
      if (typed_ && i < a.declares.size() && a.declares[i])
        label("declares" + var_note(a.declares[i]));
    }
    expr(*a.value);
  }

  void if_stmt(const If& s) {
    line("If", s.span);
    Nest n(*this);
    for (size_t i = 0; i < s.conditions.size(); ++i) {
      expr(*s.conditions[i]);
      block(i ? "Elif" : "Then", s.branches[i]);
    }
    if (s.has_else) block("Else", s.else_branch);
  }

  void stmt(const Stmt& s) {
    switch (s.kind) {
      case NodeKind::VarDecl: return var_decl(*s.as<VarDecl>());
      case NodeKind::IvarDecl:
        return line("IvarDecl " + s.as<IvarDecl>()->name + var_note(s.as<IvarDecl>()->var), s.span);
      case NodeKind::Assign: return assign(*s.as<Assign>());
      case NodeKind::ExprStmt: {
        line("ExprStmt", s.span);
        Nest n(*this);
        return expr(*s.as<ExprStmt>()->expr);
      }
      case NodeKind::If: return if_stmt(*s.as<If>());
      case NodeKind::While: {
        line("While", s.span);
        Nest n(*this);
        expr(*s.as<While>()->condition);
        return block("Body", s.as<While>()->body);
      }
      case NodeKind::DoWhile: {
        line("DoWhile", s.span);
        Nest n(*this);
        block("Body", s.as<DoWhile>()->body);
        return expr(*s.as<DoWhile>()->condition);
      }
      case NodeKind::ForRange: return for_range(*s.as<ForRange>());
      case NodeKind::ForSet: return for_set(*s.as<ForSet>());
      case NodeKind::Print: {
        static const char* const names[] = {"Print", "Print newline", "Print error"};
        line(names[static_cast<int>(s.as<Print>()->mode)], s.span);
        Nest n(*this);
        return exprs(s.as<Print>()->args);
      }
      case NodeKind::Apply: {
        line("Apply" + assembly_attrs(s.as<Apply>()->assembly), s.span);
        Nest n(*this);
        return exprs(s.as<Apply>()->assembly.args);
      }
      default: return line(node_kind_name(s.kind), s.span);
    }
  }

  void for_range(const ForRange& f) {
    line("ForRange " + f.var_name + var_note(f.var), f.span);
    Nest n(*this);
    expr(*f.lo);
    expr(*f.hi);
    block("Body", f.body);
  }

  void for_set(const ForSet& f) {
    std::string text = "ForSet " + f.var_name + " in " + f.domain + var_note(f.var);
    line(text, f.span);
    Nest n(*this);
    block("Body", f.body);
  }

  // ---- program elements

  void param(const char* what, const Param& p) {
    line(std::string(what) + (p.inout ? " inout " : " ") + p.name + var_note(p.var), p.span);
    Nest n(*this);
    if (p.type_expr) type(*p.type_expr);
  }

  void func(const FuncDecl& f) {
    std::string text = "FuncDecl " + f.name;
    if (f.exported) text += " export";
    if (f.is_extern) text += " extern";
    if (typed_ && f.frame_size > 0) text += " frame=" + std::to_string(f.frame_size);
    line(text, f.span);
    Nest n(*this);
    for (const auto& g : f.generics)
      line(std::string("Generic ") + (g.ranged ? "0:" : "") + g.name + var_note(g.var), g.span);
    for (const auto& p : f.params) param("Param", p);
    for (const auto& r : f.results) param("Result", r);
    if (!f.is_extern) block("Body", f.body);
  }

  void decl(const Decl& d) {
    switch (d.kind) {
      case NodeKind::ElementDecl: {
        const auto* e = d.as<ElementDecl>();
        line("ElementDecl " + e->name, e->span);
        Nest n(*this);
        for (const auto& f : e->fields) {
          line("Field " + f.name + type_note(f.type), f.span);
          Nest m(*this);
          if (f.type_expr) type(*f.type_expr);
        }
        return;
      }
      case NodeKind::ExternDecl: {
        const auto* e = d.as<ExternDecl>();
        line("ExternDecl " + e->name + var_note(e->var), e->span);
        Nest n(*this);
        return type(*e->type_expr);
      }
      case NodeKind::ConstDecl: {
        line("ConstDecl", d.span);
        Nest n(*this);
        return var_decl(*d.as<ConstDecl>()->decl);
      }
      case NodeKind::FuncDecl: return func(*d.as<FuncDecl>());
      case NodeKind::TestDecl: return test(*d.as<TestDecl>());
      default: return line(node_kind_name(d.kind), d.span);
    }
  }

  void test(const TestDecl& t) {
    std::string text = "TestDecl " + t.func;
    if (typed_) text += t.callee ? " -> func '" + t.callee->name + "'" : " -> unresolved";
    line(text, t.span);
    Nest n(*this);
    exprs(t.args);
    label("Expected");
    Nest m(*this);
    expr(*t.expected);
  }

  bool typed_;
  int depth_ = 0;
  std::ostringstream out_;
};

}  // namespace

std::string dump_ast(const ast::Program& program) { return Dumper(false).program(program); }

std::string dump_typed(const ast::Program& program) { return Dumper(true).program(program); }

}  // namespace simit::frontend
