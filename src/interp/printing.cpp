// Text forms of values.
#include "interp/printing.h"

#include <charconv>
#include <cmath>
#include <cstdio>

#include "interp/system_values.h"
#include "runtime/dense_linalg.h"

namespace simit::interp {

namespace {

std::string g_format(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

// The shortest text that reads back as `x`, always with a `.` or an exponent.
std::string float_literal(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x < 0 ? "-inf" : "inf";
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, x);
  std::string s(buf, res.ptr);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

std::string print_component(const Tensor& t, size_t i) {
  switch (t.kind()) {
    case ComponentKind::Int: return std::to_string(t.ints()[i]);
    case ComponentKind::Float: return g_format(t.floats()[i]);
    case ComponentKind::Bool: return t.bools()[i] ? "1" : "0";
    case ComponentKind::Complex:
      return "<" + g_format(t.complexes()[i].real()) + "," + g_format(t.complexes()[i].imag()) +
             ">";
    case ComponentKind::String: return t.strings()[i];
  }
  return "?";
}

std::string literal_component(const Tensor& t, size_t i) {
  switch (t.kind()) {
    case ComponentKind::Int: return std::to_string(t.ints()[i]);
    case ComponentKind::Float: return float_literal(t.floats()[i]);
    case ComponentKind::Bool: return t.bools()[i] ? "true" : "false";
    case ComponentKind::Complex:
      return "<" + float_literal(t.complexes()[i].real()) + "," +
             float_literal(t.complexes()[i].imag()) + ">";
    case ComponentKind::String: {
      std::string out = "\"";
      for (char ch : t.strings()[i]) {
        if (ch == '"' || ch == '\\') out += '\\';
        if (ch == '\n') {
          out += "\\n";
          continue;
        }
        out += ch;
      }
      return out + "\"";
    }
  }
  return "?";
}

// `(i, j)(k, l)`: the index of component `n`, one group per blocking level.
std::string index_text(const Shape& s, size_t n) {
  std::vector<int> idx(s.rank());
  for (int p = s.rank() - 1; p >= 0; --p) {
    idx[p] = static_cast<int>(n % s.dim(p));
    n /= s.dim(p);
  }
  std::string out;
  for (int l = 0, p = 0; l < s.levels(); ++l) {
    out += "(";
    for (int k = 0; k < s.level_order(l); ++k, ++p) out += (k ? ", " : "") + std::to_string(idx[p]);
    out += ")";
  }
  return out;
}

// Nested brackets for dimensions before the last two; `;` between rows of the last two.
void literal_dims(const Tensor& t, int dim, size_t& n, std::string& out) {
  const Shape& s = t.shape();
  const int order = s.order();
  if (dim + 2 < order) {
    for (int i = 0; i < s.dim(dim); ++i) {
      out += i ? ", [" : "[";
      literal_dims(t, dim + 1, n, out);
      out += "]";
    }
    return;
  }
  const int rows = order >= 2 ? s.dim(order - 2) : 1, cols = s.dim(order - 1);
  for (int r = 0; r < rows; ++r) {
    if (r) out += "; ";
    for (int c = 0; c < cols; ++c) out += (c ? ", " : "") + literal_component(t, n++);
  }
}

}  // namespace

void print_value(std::ostream& out, const Value& v, bool row) {
  // A system matrix prints like the dense matrix it means (LANGUAGE.md §8.4).
  if (v.kind() == Value::Kind::Matrix && v.matrix())
    return print_value(out, Value::of_tensor(dense_of(*v.matrix())), false);
  if (!v.is_tensor()) {
    if (v.kind() == Value::Kind::String) {
      out << v.as_string();
      return;
    }
    if (v.empty()) return;
    out << print_component(v.to_tensor(), 0);
    return;
  }
  const Tensor& t = v.tensor();
  const Shape& s = t.shape();
  const size_t n = t.size();
  if (!s.is_blocked() && s.order() <= 2) {
    const size_t cols = s.order() == 1 ? (row ? n : 1) : static_cast<size_t>(s.dim(1));
    for (size_t i = 0; i < n; ++i) {
      if (i) out << (cols && i % cols == 0 ? "\n" : " ");
      out << print_component(t, i);
    }
    return;
  }
  for (size_t i = 0; i < n; ++i) {
    if (i) out << "\n";
    out << index_text(s, i) << " " << print_component(t, i);
  }
}

std::string literal_text(const Value& v, bool column) {
  if (v.empty()) return "<no value>";
  if (!v.is_tensor()) return literal_component(v.to_tensor(), 0);
  const Shape& s = v.tensor().shape();
  Tensor t = v.tensor();
  if (s.uniform()) {
    t = runtime::unblock(t);
  } else {  // blocks of another order than the outer level: show every dimension
    std::vector<int> dims;
    for (int i = 0; i < s.rank(); ++i) dims.push_back(s.dim(i));
    t.reshape(Shape::of(dims));
  }
  std::string out = "[";
  size_t n = 0;
  literal_dims(t, 0, n, out);
  out += "]";
  if (t.shape().order() == 1 && column) out += "'";
  return out;
}

}  // namespace simit::interp
