// The REPL's views of set data: :sets, :fields SET (with a summary of values) and
// :print SET.FIELD[i].
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "frontend/ast.h"
#include "frontend/types.h"
#include "input_text.h"
#include "interp/printing.h"
#include "runtime/tensor.h"
#include "session.h"

namespace simit::repl {
namespace {

namespace ast = frontend::ast;
using runtime::ComponentKind;

// Component k of element e of field f, as a double (ints and bools too).
double component(const runtime::Field& f, int e, size_t k) {
  const runtime::FieldType& t = f.type();
  switch (t.kind) {
    case ComponentKind::Float: return t.single ? f.at<float>(e)[k] : f.at<double>(e)[k];
    case ComponentKind::Int: return f.at<int32_t>(e)[k];
    case ComponentKind::Bool: return f.at<bool>(e)[k] ? 1.0 : 0.0;
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}

// One element's value of a field, as a Simit literal.
std::string element_text(const runtime::Field& f, int e) {
  const runtime::FieldType& t = f.type();
  const size_t n = t.components();
  if (t.kind == ComponentKind::Complex || t.kind == ComponentKind::String) return "(not shown)";
  if (t.dims.empty()) {
    double v = component(f, e, 0);
    if (t.kind == ComponentKind::Bool) return v != 0.0 ? "true" : "false";
    if (t.kind == ComponentKind::Int) return std::to_string(static_cast<long long>(v));
    return interp::literal_text(interp::Value::of_float(v), true);
  }
  runtime::Tensor tensor(t.kind, runtime::Shape::of(t.dims));
  for (size_t k = 0; k < n; ++k) {
    double v = component(f, e, k);
    switch (t.kind) {
      case ComponentKind::Float: tensor.mutable_floats()[k] = v; break;
      case ComponentKind::Int: tensor.mutable_ints()[k] = static_cast<int32_t>(v); break;
      case ComponentKind::Bool: tensor.mutable_bools()[k] = v != 0.0; break;
      default: break;
    }
  }
  return interp::literal_text(interp::Value::of_tensor(std::move(tensor)), false);
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

const runtime::Set* Session::bound_set(const std::string& name) const {
  if (!scene_) return nullptr;
  for (const auto& [n, s] : scene_->sets)
    if (n == name) return s;
  return nullptr;
}

std::vector<std::string> Session::set_names() const {
  std::vector<std::string> out;
  if (scene_)
    for (const auto& [n, s] : scene_->sets) out.push_back(n);
  return out;
}

// The Simit type of a field as its element declares it (e.g. `vector[3](float)`).
std::string Session::field_type(const std::string& set_name, const runtime::Field& f) {
  int offset = 0;
  auto c = compile("", "", "", offset);
  if (c->ok())
    for (const ast::Variable* g : c->program->globals)
      if (g->name == set_name && g->type && g->type->kind == frontend::Type::Kind::Set &&
          g->type->element)
        for (const ast::FieldDecl& d : g->type->element->fields)
          if (d.name == f.name() && d.type) return frontend::to_string(*d.type);
  return f.type().str();
}

void Session::list_sets() {
  int offset = 0;
  auto c = compile("", "", "", offset);
  bool any = false;
  if (c->ok()) {
    for (const ast::Variable* g : c->program->globals) {
      if (g->kind != ast::Variable::Kind::Extern || !g->type ||
          g->type->kind != frontend::Type::Kind::Set)
        continue;
      any = true;
      out_ << g->name << " : " << frontend::to_string(*g->type);
      if (const runtime::Set* s = bound_set(g->name)) {
        out_ << "  " << s->size() << " elements; fields";
        for (int f = 0; f < s->field_count(); ++f) out_ << (f ? ", " : " ") << s->field(f).name();
        if (s->field_count() == 0) out_ << " (none)";
      } else {
        out_ << "  (not bound: :scene binds sets)";
      }
      out_ << "\n";
    }
  }
  if (!any) out_ << "no extern sets (declare them, :load a program or :scene a scene)\n";
}

void Session::list_fields(const std::string& set_name) {
  if (set_name.empty()) {
    err_ << ":fields needs a set name (:sets lists them)\n";
    return;
  }
  const runtime::Set* s = bound_set(set_name);
  if (!s) {
    err_ << ":fields: no bound set '" << set_name << "' (:sets lists them)\n";
    return;
  }
  out_ << set_name << ": " << s->size() << " elements\n";
  for (int fi = 0; fi < s->field_count(); ++fi) {
    const runtime::Field& f = s->field(fi);
    const runtime::FieldType& t = f.type();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    long long bad = 0;
    const size_t n = t.components();
    for (int e = 0; e < s->size(); ++e)
      for (size_t k = 0; k < n; ++k) {
        double v = component(f, e, k);
        if (!std::isfinite(v)) {
          ++bad;
          continue;
        }
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    out_ << "  " << f.name() << " : " << field_type(set_name, f);
    if (t.kind == ComponentKind::Complex || t.kind == ComponentKind::String) {
      out_ << "\n";
      continue;
    }
    if (lo <= hi) out_ << "  min " << number(lo) << "  max " << number(hi);
    out_ << "  NaN/Inf " << bad << "\n";
  }
}

// `SET.FIELD[i]` prints element i; `SET.FIELD` prints the first elements (print_limit).
void Session::print_field(const std::string& arg) {
  std::string a = trim(arg);
  size_t dot = a.find('.');
  if (a.empty() || dot == std::string::npos) {
    err_ << ":print needs SET.FIELD[i] or SET.FIELD\n";
    return;
  }
  std::string set_name = a.substr(0, dot), field = a.substr(dot + 1);
  int index = -1;
  size_t bracket = field.find('[');
  if (bracket != std::string::npos) {
    std::string inside = field.substr(bracket + 1);
    field = trim(field.substr(0, bracket));
    if (inside.empty() || inside.back() != ']') {
      err_ << ":print: expected ']' after the element index\n";
      return;
    }
    inside = trim(inside.substr(0, inside.size() - 1));
    auto [end, ec] = std::from_chars(inside.data(), inside.data() + inside.size(), index);
    if (ec != std::errc() || end != inside.data() + inside.size()) index = -1;
    if (index < 0) {
      err_ << ":print: the element index must be a whole number >= 0, not '" << inside << "'\n";
      return;
    }
  }
  const runtime::Set* s = bound_set(set_name);
  if (!s) {
    err_ << ":print: no bound set '" << set_name << "' (:sets lists them)\n";
    return;
  }
  int fi = s->field_index(field);
  if (fi < 0) {
    err_ << ":print: set '" << set_name << "' has no field '" << field << "'\n";
    return;
  }
  const runtime::Field& f = s->field(fi);
  if (index >= 0) {
    if (index >= s->size()) {
      err_ << ":print: " << set_name << " has " << s->size() << " elements; " << index
           << " is out of range\n";
      return;
    }
    out_ << element_text(f, index) << " : " << field_type(set_name, f) << "\n";
    return;
  }
  out_ << set_name << "." << field << " : " << field_type(set_name, f) << ", " << s->size()
       << " elements\n";
  const int shown = std::min(s->size(), options_.print_limit);
  for (int e = 0; e < shown; ++e) out_ << "[" << e << "] " << element_text(f, e) << "\n";
  if (shown < s->size())
    out_ << "... " << (s->size() - shown) << " more (:fields " << set_name
         << " summarises; :set print_limit N shows more)\n";
}

}  // namespace simit::repl
