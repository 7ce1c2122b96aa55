// The random-program generator's expressions and statements: float, int and boolean
// expressions over a function's locals, fields and arguments, and the statements of element
// functions and helpers.
#include <cstdio>

#include "random_program_gen.h"

namespace simit::jit::random_programs {

std::string ProgramGen::number() {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", real(-2.0, 2.0));
  std::string s = buf;
  return s[0] == '-' ? "(" + s + ")" : s;
}

std::string ProgramGen::literal(Shape s) {
  if (s.scalar()) return number();
  auto entry = [&] {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", real(-2.0, 2.0));
    return std::string(buf);
  };
  std::string out = "[";
  if (s.vector()) {
    for (int i = 0; i < s.rows; ++i) out += (i ? ", " : "") + entry();
    return out + "]'";
  }
  for (int i = 0; i < s.rows; ++i) {
    if (i) out += "; ";
    for (int j = 0; j < s.cols; ++j) out += (j ? ", " : "") + entry();
  }
  return out + "]";
}

Shape ProgramGen::random_shape() {
  switch (pick(0, 5)) {
    case 0:
    case 1: return {};
    case 2:
    case 3: return {pick(2, 4), 0};
    default: return {pick(2, 4), pick(2, 4)};
  }
}

Global ProgramGen::random_global(bool edge_map) {
  Global g;
  const int k = pick(0, 9);
  g.of = k < 5 ? Global::Of::Verts : k < 9 || !edge_map ? Global::Of::Matrix : Global::Of::Edges;
  g.block = coin(0.7) ? main_block_ : one_of(std::vector<int>{0, 2, 3, 4});
  if (g.matrix()) {
    g.cblock = g.block && coin(0.15) ? pick(2, 4) : g.block;
    if (edge_map && coin(0.15)) g.of = Global::Of::EdgeMatrix;
  }
  return g;
}

// ---------------------------------------------------------------------------
// Expressions

std::vector<Var> ProgramGen::visible(const Fn& f) const {
  std::vector<Var> out;
  for (const auto& s : f.scopes) out.insert(out.end(), s.begin(), s.end());
  return out;
}

// An int that is a valid index below n: a literal or a loop variable bounded by n, now and then
// mod or an integer division of a loop variable of any bound.
std::string ProgramGen::index_below(const Fn& f, int n) {
  std::vector<std::string> c;
  std::vector<Var> loops;
  for (const Var& v : visible(f)) {
    if (v.bound > 0 && v.bound <= n) c.push_back(v.name);
    if (v.bound > 0) loops.push_back(v);
  }
  if (!loops.empty() && coin(0.15)) return loop_index(one_of(loops), n);
  if (!c.empty() && coin(0.6)) return one_of(c);
  return std::to_string(pick(0, n - 1));
}

// An index below n computed from the loop variable v (0 <= v < v.bound) with mod and `/`: once
// the loop is unrolled, their operands are constants. The forms with a negative operand are in
// range only under the language's truncating rules (mod takes the dividend's sign, `/` rounds
// toward zero); a floored mod or division would compute another index, or one out of range.
std::string ProgramGen::loop_index(const Var& v, int n) {
  const std::string i = v.name;
  const int top = v.bound - 1;  // v's largest value; its smallest is 0 or more
  switch (pick(0, 3)) {
    case 1: {
      // mod(v - c, m) lies in (-m, m): shifted by m - 1 it lies in [0, 2m - 2], below n.
      const int m = pick(1, (n + 1) / 2), c = pick(1, 3);
      return "(mod(" + i + " - " + std::to_string(c) + ", " + std::to_string(m) + ") + " +
             std::to_string(m - 1) + ")";
    }
    case 2: {
      // (v + c) / d and -((v + c) / (-d)), both in [0, (top + c) / d].
      const int c = pick(0, 2), d = pick(1, 3);
      if ((top + c) / d >= n) break;
      const std::string sum = "(" + i + " + " + std::to_string(c) + ")";
      if (coin(0.5)) return "(" + sum + " / " + std::to_string(d) + ")";
      return "(-(" + sum + " / (-" + std::to_string(d) + ")))";
    }
    case 3: {
      // (v - c) / d + c / d: 0 at v = 0 (truncation), at most (top - c) / d + c / d.
      const int c = pick(1, 3), d = pick(1, 3);
      if ((top - c) / d + c / d >= n) break;
      return "((" + i + " - " + std::to_string(c) + ") / " + std::to_string(d) + " + " +
             std::to_string(c / d) + ")";
    }
    default: break;
  }
  // mod(v + c, +-n): the dividend is not negative, so the result lies in [0, n).
  const std::string d = coin(0.7) ? std::to_string(n) : "(-" + std::to_string(n) + ")";
  return "mod(" + i + " + " + std::to_string(pick(0, 3)) + ", " + d + ")";
}

std::string ProgramGen::endpoint(const Fn& f) {
  return f.tuple + "(" + index_below(f, sets_.arity) + ")";
}

// An element of the function that indexes a global of this kind ("" if none).
std::string ProgramGen::member_for(const Fn& f, const Global& g) {
  if (f.elem.empty()) return "";
  if (g.of == Global::Of::Edges || g.of == Global::Of::EdgeMatrix) return f.edge ? f.elem : "";
  if (!f.edge) return f.elem;
  return f.tuple.empty() ? "" : endpoint(f);
}

std::string ProgramGen::fleaf(Fn& f, Shape s) {
  std::vector<std::string> c;
  for (const Var& v : visible(f)) {
    if (v.kind != Kind::Float) continue;
    if (v.shape == s) c.push_back(v.name);
    if (s.scalar() && v.shape.vector())
      c.push_back(v.name + "(" + index_below(f, v.shape.rows) + ")");
    if (s.scalar() && v.shape.matrix())
      c.push_back(v.name + "(" + index_below(f, v.shape.rows) + ", " +
                  index_below(f, v.shape.cols) + ")");
    if (s.vector() && v.shape.matrix() && v.shape.rows == s.rows && coin(0.2))
      c.push_back(v.name + "(:, " + index_below(f, v.shape.cols) + ")");
  }
  auto fields = [&](const std::string& base, const std::vector<FieldSpec>& fs) {
    for (const FieldSpec& fd : fs) {
      if (fd.kind != Kind::Float) continue;
      const std::string r = base + "." + fd.name;
      if (fd.shape == s) c.push_back(r);
      if (s.scalar() && fd.shape.vector())
        c.push_back(r + "(" + index_below(f, fd.shape.rows) + ")");
      if (s.scalar() && fd.shape.matrix())
        c.push_back(r + "(" + index_below(f, fd.shape.rows) + ", " + index_below(f, fd.shape.cols) +
                    ")");
    }
  };
  if (!f.elem.empty()) fields(f.elem, elem_fields(f));
  if (!f.tuple.empty()) fields(endpoint(f), sets_.vfields);
  for (const auto& [name, g] : f.vectors) {
    const std::string m = member_for(f, g);
    if (m.empty()) continue;
    if (g.block == 0 && s.scalar()) c.push_back(name + "(" + m + ")");
    if (g.block && s.vector() && s.rows == g.block) c.push_back(name + "(" + m + ")");
    if (g.block && s.scalar()) c.push_back(name + "(" + m + ")(" + index_below(f, g.block) + ")");
  }
  if (s.scalar()) {
    c.push_back("g_s");
    c.push_back("k_s");
  }
  if (s.vector() && s.rows == 3) c.push_back("k_v3");
  if (s == Shape{2, 2}) c.push_back("k_m22");
  if (c.empty() || coin(0.15)) return literal(s);
  return one_of(c);
}

std::string ProgramGen::fexpr(Fn& f, Shape s, int depth) {
  if (depth <= 0 || coin(0.25)) return fleaf(f, s);
  if (s.scalar()) return fscalar(f, depth - 1);
  if (s.vector()) return fvector(f, s, depth - 1);
  return fmatrix(f, s, depth - 1);
}

// A float that is never zero and not small: a divisor.
std::string ProgramGen::denominator(Fn& f, int depth) {
  switch (pick(0, 2)) {
    case 0: return "(abs(" + fexpr(f, {}, depth) + ") + 0.5)";
    case 1: return "(2.0 + sin(" + fexpr(f, {}, depth) + "))";
    default: return "1.7500";
  }
}

// The helper's last argument, if the function has one to give ("" and false otherwise).
bool ProgramGen::helper_tail(Fn& f, const Helper& h, std::string& arg) {
  using T = Helper::Takes;
  arg.clear();
  switch (h.takes) {
    case T::Nothing: return true;
    case T::Vertex: arg = !f.edge ? f.elem : f.tuple.empty() ? "" : endpoint(f); break;
    case T::Tuple: arg = f.tuple; break;
    case T::InoutVertex:
      arg = !f.edge && f.elem_inout ? f.elem : f.tuple_inout ? endpoint(f) : "";
      break;
  }
  return !arg.empty();
}

std::string ProgramGen::helper_args(Fn& f, const Helper& h, int depth, bool& ok) {
  std::string tail, out;
  ok = helper_tail(f, h, tail);
  for (size_t i = 0; i < h.params.size(); ++i)
    out += (i ? ", " : "") + fexpr(f, h.params[i], depth);
  if (!tail.empty()) out += (h.params.empty() ? "" : ", ") + tail;
  return out;
}

std::string ProgramGen::helper_call(Fn& f, Shape s, int depth) {
  std::vector<const Helper*> c;
  for (const Helper& h : helpers_)
    if (h.results.size() == 1 && h.results[0] == s) c.push_back(&h);
  if (c.empty()) return "";
  const Helper& h = *one_of(c);
  bool ok = false;
  const std::string args = helper_args(f, h, depth, ok);
  return ok ? h.name + "(" + args + ")" : "";
}

std::string ProgramGen::fscalar(Fn& f, int d) {
  const Shape s{};
  auto e = [&] { return fexpr(f, s, d); };
  switch (pick(0, 15)) {
    case 0: return "(" + e() + " + " + e() + ")";
    case 1: return "(" + e() + " - " + e() + ")";
    case 2: return "(" + e() + " * " + e() + ")";
    case 3: return "(" + e() + " / " + denominator(f, d) + ")";
    case 4: return "(-" + e() + ")";
    case 5: return (coin(0.5) ? "sin(" : "cos(") + e() + ")";
    case 6: return "sqrt(abs(" + e() + "))";
    case 7: return coin(0.5) ? "exp(sin(" + e() + "))" : "exp(min(max(" + e() + ", -2.0), 2.0))";
    case 8: return (coin(0.5) ? "max(" : "min(") + e() + ", " + e() + ")";
    case 9: {
      const Shape v{pick(2, 4), 0};
      const int k = pick(0, 2);
      if (k == 0) return "dot(" + fexpr(f, v, d) + ", " + fexpr(f, v, d) + ")";
      if (k == 1) return "norm(" + fexpr(f, v, d) + ")";
      return "(" + fexpr(f, v, d) + "' * " + fexpr(f, v, d) + ")";
    }
    case 10: {
      const int n = pick(2, 4);
      const char* det = n == 2 ? "det2(" : n == 3 ? "det(" : "det4(";
      return det + fexpr(f, {n, n}, d) + ")";
    }
    case 11: {
      std::string h = helper_call(f, s, d);
      return h.empty() ? fleaf(f, s) : h;
    }
    case 12:
      switch (pick(0, 2)) {
        case 0: return "log(abs(" + e() + ") + 1.0)";
        case 1: return "atan2(" + e() + ", " + e() + ")";
        default: return "pow(abs(" + e() + ") + 0.5, 1.5)";
      }
    default: return fleaf(f, s);
  }
}

// A value of shape s through a product too large to unroll (the JIT tiles it): K x K outer
// products (loops) multiplied, scaled and added element-wise (loops over their scratch
// arrays), then brought to s through products with K-vectors, on the right or the left.
std::string ProgramGen::big_product(Fn& f, Shape s, int d) {
  const int k = pick(13, 24);
  auto kv = [&] { return literal({k, 0}); };
  auto big = [&] { return "((" + kv() + " * " + kv() + "') * (" + kv() + " * " + kv() + "'))"; };
  const std::string mixed = "(" + fexpr(f, {}, d) + " * " + big() + " + " + big() + ")";
  const std::string left = "(" + fexpr(f, {s.rows, 0}, d) + " * " + kv() + "')";
  // The K-vector on either side of the matrix (a loop over rows or over columns).
  const std::string reduced =
      coin(0.5) ? "(" + mixed + " * " + kv() + ")" : "(" + kv() + "' * " + mixed + ")'";
  if (s.vector()) return "(" + left + " * " + reduced + ")";
  return "(" + left + " * (" + mixed + " * (" + kv() + " * " + fexpr(f, {s.cols, 0}, d) + "')))";
}

std::string ProgramGen::fvector(Fn& f, Shape s, int d) {
  if (coin(0.01)) return big_product(f, s, d);
  auto e = [&] { return fexpr(f, s, d); };
  switch (pick(0, 11)) {
    case 0: return "(" + e() + " + " + e() + ")";
    case 1: return "(" + e() + " - " + e() + ")";
    case 2: return "(" + fexpr(f, {}, d) + " * " + e() + ")";
    case 3: return "(" + e() + " * " + fexpr(f, {}, d) + ")";
    case 4: return "(" + e() + " / " + denominator(f, d) + ")";
    case 5: return "(-" + e() + ")";
    case 6: return "(" + e() + " .* " + e() + ")";
    case 7: {
      const int k = pick(2, 4);
      return "(" + fexpr(f, {s.rows, k}, d) + " * " + fexpr(f, {k, 0}, d) + ")";
    }
    case 8:
      if (s.rows == 3) return "cross(" + e() + ", " + e() + ")";
      return e();
    case 9: {
      const int k = pick(2, 4);
      return "(" + fexpr(f, {k, 0}, d) + "' * " + fexpr(f, {k, s.rows}, d) + ")'";
    }
    case 10: {
      std::string h = helper_call(f, s, d);
      return h.empty() ? fleaf(f, s) : h;
    }
    default: return fleaf(f, s);
  }
}

std::string ProgramGen::fmatrix(Fn& f, Shape s, int d) {
  if (coin(0.02)) return big_product(f, s, d);
  auto e = [&] { return fexpr(f, s, d); };
  switch (pick(0, 10)) {
    case 0: return "(" + e() + " + " + e() + ")";
    case 1: return "(" + e() + " - " + e() + ")";
    case 2: return "(" + fexpr(f, {}, d) + " * " + e() + ")";
    case 3: return "(" + e() + " .* " + e() + ")";
    case 4: return "(-" + e() + ")";
    case 5: {
      const int k = pick(2, 4);
      return "(" + fexpr(f, {s.rows, k}, d) + " * " + fexpr(f, {k, s.cols}, d) + ")";
    }
    case 6: return fexpr(f, {s.cols, s.rows}, d) + "'";
    case 7: return "(" + fexpr(f, {s.rows, 0}, d) + " * " + fexpr(f, {s.cols, 0}, d) + "')";
    case 8: {
      if (s.rows != s.cols) return e();
      const int n = s.rows;
      const char* inv = n == 2 ? "inv2(" : n == 3 ? "inv(" : "inv4(";
      return inv + ("wc" + std::to_string(n) + "(") + e() + "))";
    }
    case 9: {
      std::string h = helper_call(f, s, d);
      return h.empty() ? fleaf(f, s) : h;
    }
    default: return fleaf(f, s);
  }
}

std::string ProgramGen::ileaf(Fn& f) {
  std::vector<std::string> c;
  for (const Var& v : visible(f))
    if (v.kind == Kind::Int) c.push_back(v.name);
  auto fields = [&](const std::string& base, const std::vector<FieldSpec>& fs) {
    for (const FieldSpec& fd : fs)
      if (fd.kind == Kind::Int) c.push_back(base + "." + fd.name);
  };
  if (!f.elem.empty()) fields(f.elem, elem_fields(f));
  if (!f.tuple.empty()) fields(endpoint(f), sets_.vfields);
  if (c.empty() || coin(0.3)) return std::to_string(pick(0, 4));
  return one_of(c);
}

std::string ProgramGen::iexpr(Fn& f, int depth) {
  if (depth <= 0 || coin(0.4)) return ileaf(f);
  auto e = [&] { return iexpr(f, depth - 1); };
  switch (pick(0, 10)) {
    case 0:
    case 1:
    case 2: return "(" + e() + " + " + e() + ")";
    case 3:
    case 4: return "(" + e() + " - " + e() + ")";
    case 5:
    case 6: return "(" + e() + " * " + ileaf(f) + ")";
    case 7: return "mod(" + e() + ", " + int_divisor(f) + ")";
    case 8: return "(" + e() + " / " + int_divisor(f) + ")";
    default: return ileaf(f);
  }
}

// The right operand of mod or `/`: a constant of either sign, or an int expression that is
// never 0 nor -1 (x * x is never -1, -2 or 3 modulo 4, so neither x * x + 1 nor -2 - x * x is 0
// or -1, even when x * x wraps around). In programs with raw divisions, also a bare leaf.
std::string ProgramGen::int_divisor(Fn& f) {
  if (raw_divisions_ && coin(0.5)) return ileaf(f);
  switch (pick(0, 3)) {
    case 0: {
      const std::string x = ileaf(f);
      return "(" + x + " * " + x + " + 1)";
    }
    case 1: {
      const std::string x = ileaf(f);
      return "(-2 - " + x + " * " + x + ")";
    }
    default: return one_of(std::vector<std::string>{"3", "2", "5", "(-2)", "(-3)", "7"});
  }
}

std::string ProgramGen::cond(Fn& f, int depth) {
  static const std::vector<std::string> ops = {"<", "<=", ">", ">=", "!="};
  auto fcmp = [&] {
    return "(" + fexpr(f, {}, depth) + ") " + one_of(ops) + " (" + fexpr(f, {}, depth) + ")";
  };
  const int k = pick(0, depth > 0 ? 9 : 4);
  switch (k) {
    case 0:
    case 1: return fcmp();
    case 2: {
      const std::string op = coin(0.3) ? "==" : one_of(ops);
      return "(" + iexpr(f, 1) + ") " + op + " (" + iexpr(f, 1) + ")";
    }
    case 3:
    case 4: {
      std::vector<std::string> c;
      for (const Var& v : visible(f))
        if (v.kind == Kind::Bool) c.push_back(v.name);
      auto fields = [&](const std::string& base, const std::vector<FieldSpec>& fs) {
        for (const FieldSpec& fd : fs)
          if (fd.kind == Kind::Bool) c.push_back(base + "." + fd.name);
      };
      if (!f.elem.empty()) fields(f.elem, elem_fields(f));
      if (!f.tuple.empty()) fields(endpoint(f), sets_.vfields);
      if (c.empty()) return fcmp();
      return one_of(c);
    }
    case 5: return "not (" + cond(f, depth - 1) + ")";
    case 6: return "(" + cond(f, depth - 1) + ") and (" + cond(f, depth - 1) + ")";
    case 7: return "(" + cond(f, depth - 1) + ") or (" + cond(f, depth - 1) + ")";
    case 8: return "(" + cond(f, depth - 1) + ") xor (" + cond(f, depth - 1) + ")";
    default:
      return "(" + fexpr(f, {}, 1) + ") < (" + fexpr(f, {}, 1) + ") <= (" + fexpr(f, {}, 1) + ")";
  }
}

// ---------------------------------------------------------------------------
// Statements

void ProgramGen::line(Fn& f, const std::string& s) {
  f.body << std::string(static_cast<size_t>(2 * f.indent), ' ') << s << "\n";
  ++f.statements;
}

void ProgramGen::stmts(Fn& f, int count, int depth) {
  for (int i = 0; i < count; ++i) stmt(f, depth);
}

void ProgramGen::stmt(Fn& f, int depth) {
  const int k = pick(0, 15);
  if (k < 3) return decl_stmt(f);
  if (k < 5) return assign_stmt(f);
  if (k < 7 && depth > 0) return if_stmt(f, depth);
  if (k < 8 && depth > 0) return for_stmt(f, depth);
  if (k < 11 && !f.results.empty()) return result_write(f, one_of(f.results));
  if (k < 13 && f.elem_inout) return field_write(f);
  if (k < 14) return multi_call(f);
  decl_stmt(f);
}

void ProgramGen::decl_stmt(Fn& f) {
  Var v;
  v.name = fresh("t");
  const int k = pick(0, 9);
  if (k == 0) {
    v.kind = Kind::Int;
    v.writable = true;
    line(f, "var " + v.name + " = " + iexpr(f, 2) + ";");
    if (coin(0.25)) guarded_division(f, v);
  } else if (k == 1) {
    v.kind = Kind::Bool;
    v.writable = true;
    line(f, "var " + v.name + " : bool = " + cond(f, 1) + ";");
  } else {
    v.shape = random_shape();
    if (!v.shape.scalar() && coin(0.15)) return broadcast_decl(f, v);
    const std::string e = fexpr(f, v.shape, 3);
    v.writable = coin(0.5);
    if (!v.writable)
      line(f, v.name + " = " + e + ";");
    else if (coin(0.5))
      line(f, "var " + v.name + " : " + v.shape.type() + " = " + e + ";");
    else
      line(f, "var " + v.name + " = " + e + ";");
  }
  declare(f, v);
}

// A tensor declared from a scalar, which every component takes (`var E : matrix[3,3](float) =
// 1.0;`, `const c : vector[3](float) = g_s;`), now and then a vector of one component. A write
// of one component may follow, or a use of the whole tensor (a product, a norm, an element-wise
// operation): a tracer that kept the scalar computes with it silently only where nothing
// indexes the tensor.
void ProgramGen::broadcast_decl(Fn& f, Var v) {
  if (coin(0.1)) v.shape = {1, 0};
  const std::string e = coin(0.4) ? number() : fexpr(f, {}, 2);
  v.writable = coin(0.7);
  line(f, (v.writable ? "var " : "const ") + v.name + " : " + v.shape.type() + " = " + e + ";");
  declare(f, v);
  const int k = pick(0, 9);
  if (v.writable && k < 3) {
    std::string at = index_below(f, v.shape.rows);
    if (v.shape.matrix()) at += ", " + index_below(f, v.shape.cols);
    return line(f, v.name + "(" + at + ") = " + fexpr(f, {}, 2) + ";");
  }
  if (k >= 8) return;
  Var u;
  u.name = fresh("t");
  const Shape s = v.shape;
  std::string use;
  if (s.matrix() && coin(0.5)) {
    u.shape = {s.rows, 0};
    use = v.name + " * " + fexpr(f, {s.cols, 0}, 2);
  } else if (s.matrix()) {
    u.shape = {s.cols, 0};
    use = "(" + v.name + "' * " + fexpr(f, {s.rows, 0}, 2) + ")";
  } else if (s.rows == 1 || coin(0.4)) {
    use = (coin(0.5) ? "norm(" + v.name + ")" : v.name + "' * " + v.name) + " * " + fexpr(f, {}, 2);
  } else {
    u.shape = s;
    use = v.name + (coin(0.5) ? " .* " : " - ") + fexpr(f, s, 2);
  }
  line(f, u.name + " = " + use + ";");
  declare(f, u);
}

// The int v divided by a leaf that may be zero, under a condition that it is not: a kernel that
// computes both branches of an if (four elements at once) must not divide by the zero.
void ProgramGen::guarded_division(Fn& f, const Var& v) {
  const std::string d = ileaf(f);
  line(f, "if " + d + " != 0");
  ++f.indent;
  line(f, v.name + " = " +
              (coin(0.5) ? "mod(" + iexpr(f, 1) + ", " + d + ")"
                         : "(" + iexpr(f, 1) + " / " + d + ")") +
              ";");
  --f.indent;
  line(f, "end");
}

void ProgramGen::assign_stmt(Fn& f) {
  std::vector<Var> c;
  for (const Var& v : visible(f))
    if (v.writable) c.push_back(v);
  if (c.empty()) return decl_stmt(f);
  const Var v = one_of(c);
  if (v.kind == Kind::Int) return line(f, v.name + " = " + iexpr(f, 2) + ";");
  if (v.kind == Kind::Bool) return line(f, v.name + " = " + cond(f, 1) + ";");
  // A vector of one component (a broadcast declaration's) takes a component or a scalar only.
  const int k = v.shape.rows == 1 ? pick(0, 1) : pick(0, 5);
  if (k == 0 && v.shape.vector())
    return line(f, v.name + "(" + index_below(f, v.shape.rows) + ") = " + fexpr(f, {}, 2) + ";");
  if (k == 0 && v.shape.matrix())
    return line(f, v.name + "(" + index_below(f, v.shape.rows) + ", " +
                       index_below(f, v.shape.cols) + ") = " + fexpr(f, {}, 2) + ";");
  if (k == 1 && !v.shape.scalar()) return line(f, v.name + " = " + fexpr(f, {}, 2) + ";");
  line(f, v.name + " = " + fexpr(f, v.shape, 3) + ";");
}

void ProgramGen::if_stmt(Fn& f, int depth) {
  // A variable declared before the if, for the branches to assign.
  if (coin(0.5)) {
    Var v;
    v.name = fresh("t");
    v.shape = random_shape();
    v.writable = true;
    line(f, "var " + v.name + " : " + v.shape.type() + " = " + fexpr(f, v.shape, 1) + ";");
    declare(f, v);
  }
  const int elifs = pick(0, 2);
  const bool has_else = coin(0.6);
  auto branch = [&] {
    ++f.indent;
    f.scopes.emplace_back();
    stmts(f, pick(1, 3), depth - 1);
    f.scopes.pop_back();
    --f.indent;
  };
  line(f, "if " + cond(f, 2));
  branch();
  for (int i = 0; i < elifs; ++i) {
    line(f, "elif " + cond(f, 2));
    branch();
  }
  if (has_else) {
    line(f, "else");
    branch();
  }
  line(f, "end");
}

void ProgramGen::for_stmt(Fn& f, int depth) {
  Var i;
  i.name = fresh("i");
  i.kind = Kind::Int;
  i.bound = !f.tuple.empty() && coin(0.5) ? sets_.arity : pick(1, 4);
  const int lo = coin(0.8) ? 0 : pick(0, i.bound - 1);
  line(f, "for " + i.name + " in " + std::to_string(lo) + ":" + std::to_string(i.bound));
  ++f.indent;
  f.scopes.push_back({i});
  stmts(f, pick(1, 3), depth - 1);
  f.scopes.pop_back();
  --f.indent;
  line(f, "end");
}

void ProgramGen::result_write(Fn& f, const std::pair<std::string, Global>& r) {
  const auto& [name, g] = r;
  std::string at;
  if (g.matrix()) {
    const std::string a = member_for(f, g), b = member_for(f, g.cols());
    at = name + "(" + a + ", " + b + ")";
  } else {
    at = name + "(" + member_for(f, g) + ")";
  }
  const Shape block = g.block == 0 ? Shape{}
                      : g.matrix() ? Shape{g.block, g.cblock}
                                   : Shape{g.block, 0};
  if (g.block && coin(0.25)) {
    std::string ix = "(" + index_below(f, g.block);
    if (block.matrix()) ix += ", " + index_below(f, g.cblock);
    return line(f, at + ix + ") = " + fexpr(f, {}, 2) + ";");
  }
  line(f, at + " = " + fexpr(f, block, 3) + ";");
}

void ProgramGen::field_write(Fn& f) {
  const bool endpoint_field = f.tuple_inout && coin(0.4);
  const FieldSpec& fd = one_of(endpoint_field ? sets_.vfields : elem_fields(f));
  const std::string target = (endpoint_field ? endpoint(f) : f.elem) + "." + fd.name;
  if (fd.kind == Kind::Int) return line(f, target + " = " + iexpr(f, 2) + ";");
  if (fd.kind == Kind::Bool) return line(f, target + " = " + cond(f, 1) + ";");
  if (fd.shape.matrix() && coin(0.3))
    return line(f, target + "(" + index_below(f, fd.shape.rows) + ", " +
                       index_below(f, fd.shape.cols) + ") = " + fexpr(f, {}, 2) + ";");
  if (fd.shape.vector() && coin(0.3))
    return line(f, target + "(" + index_below(f, fd.shape.rows) + ") = " + fexpr(f, {}, 2) + ";");
  line(f, target + " = " + fexpr(f, fd.shape, 3) + ";");
}

// `a, b = h(...)` with a helper of two results.
void ProgramGen::multi_call(Fn& f) {
  std::vector<const Helper*> c;
  for (const Helper& h : helpers_)
    if (h.results.size() != 1) c.push_back(&h);
  if (c.empty()) return decl_stmt(f);
  const Helper& h = *one_of(c);
  bool ok = false;
  const std::string args = helper_args(f, h, 2, ok);
  if (!ok) return decl_stmt(f);
  if (h.results.empty()) return line(f, h.name + "(" + args + ");");
  // Into new names, or into writable variables of the right shapes.
  std::vector<std::string> targets;
  for (const Shape& r : h.results) {
    std::vector<std::string> vars;
    for (const Var& v : visible(f))
      if (v.writable && v.kind == Kind::Float && v.shape == r) vars.push_back(v.name);
    if (!vars.empty() && coin(0.4) &&
        (targets.empty() || targets.back() != vars.front() || vars.size() > 1)) {
      std::string t = one_of(vars);
      while (!targets.empty() && t == targets.back()) t = one_of(vars);
      targets.push_back(t);
      continue;
    }
    Var v;
    v.name = fresh("t");
    v.shape = r;
    targets.push_back(v.name);
    declare(f, v);
  }
  line(f, targets[0] + ", " + targets[1] + " = " + h.name + "(" + args + ");");
}

}  // namespace simit::jit::random_programs
