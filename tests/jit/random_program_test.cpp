// Random Simit programs, generated from a seed, run through the interpreter and the tracing JIT
// (threshold 0) and compared bit for bit (up to the sign of a zero): every result of the exported
// function and every field of every set, after each of several calls. SIMIT_RANDOM_PROGRAMS=N runs
// N programs, from SIMIT_RANDOM_SEED (default 1); SIMIT_RANDOM_PRINT=1 prints each program and its
// traces.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "api/engine.h"
#include "interp/runtime_error.h"

namespace simit::jit {
namespace {

using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;
using interp::Value;

// Programs per run unless SIMIT_RANDOM_PROGRAMS says otherwise: a few hundred fit in CI.
constexpr long kDefaultPrograms = 400;

// ---------------------------------------------------------------------------
// Types the generator reasons about

enum class Kind { Float, Int, Bool };

// A float scalar (0, 0), a column vector[rows] (rows, 0) or a matrix[rows, cols].
struct Shape {
  int rows = 0, cols = 0;
  bool scalar() const { return rows == 0; }
  bool vector() const { return rows > 0 && cols == 0; }
  bool matrix() const { return cols > 0; }
  bool operator==(const Shape&) const = default;
  std::string type() const {
    if (scalar()) return "float";
    if (vector()) return "vector[" + std::to_string(rows) + "](float)";
    return "matrix[" + std::to_string(rows) + "," + std::to_string(cols) + "](float)";
  }
};

std::string type_of(Kind k, Shape s) {
  if (k == Kind::Int) return "int";
  if (k == Kind::Bool) return "bool";
  return s.type();
}

struct Var {
  std::string name;
  Kind kind = Kind::Float;
  Shape shape;
  bool writable = false;
  int bound = 0;  // a loop variable: its values lie below this
};

struct FieldSpec {
  std::string name;
  Kind kind = Kind::Float;
  Shape shape;
  bool single = false;  // binary32 storage (a float field)
};

// A global tensor: a vector over verts or edges, or a matrix over verts x verts or edges x
// verts, with float components (block 0) or vector[block] / matrix[block, cblock] blocks.
struct Global {
  enum class Of { Verts, Edges, Matrix, EdgeMatrix } of = Of::Verts;
  int block = 0;
  int cblock = 0;  // a matrix's blocks' columns
  bool operator==(const Global&) const = default;
  bool matrix() const { return of == Of::Matrix || of == Of::EdgeMatrix; }
  bool square() const { return of == Of::Matrix && block == cblock; }
  Global rows() const { return {of == Of::Matrix ? Of::Verts : Of::Edges, block, 0}; }
  Global cols() const { return {Of::Verts, cblock, 0}; }
  std::string type() const {
    const std::string b = std::to_string(block);
    if (matrix())
      return std::string(of == Of::Matrix ? "matrix[verts,verts](" : "matrix[edges,verts](") +
             (block ? "matrix[" + b + "," + std::to_string(cblock) + "](float))" : "float)");
    const std::string set = of == Of::Verts ? "verts" : "edges";
    return block ? "vector[" + set + "](vector[" + b + "](float))" : "vector[" + set + "](float)";
  }
};

struct Helper {
  std::string name;
  std::vector<Shape> params;
  // A last parameter: nothing, a vertex, the endpoint tuple, or an inout vertex (then the
  // helper has no results and updates the vertex's fields).
  enum class Takes { Nothing, Vertex, Tuple, InoutVertex } takes = Takes::Nothing;
  std::vector<Shape> results;
};

// The sets a program runs on, with their field values; built once per executor.
struct SetData {
  int verts = 1, edges = 1, arity = 1;
  std::vector<int32_t> endpoints;
  std::vector<FieldSpec> vfields, efields;
  std::vector<std::vector<double>> vvalues, evalues;  // per field, all components
};

struct Generated {
  std::string text;
  SetData sets;
  double g_s = 0.0;
  bool float32 = false;    // the engines' float32 mode
  uint64_t host_seed = 0;  // drives the host's changes between calls
  bool topology_change = false;
};

// ---------------------------------------------------------------------------
// The generator

// The function being generated: its scopes and what its element parameters are.
struct Fn {
  std::vector<std::vector<Var>> scopes{{}};
  std::string elem;   // the element parameter, "" if none
  bool edge = false;  // whether the element is an edge
  bool elem_inout = false;
  std::string tuple;  // the endpoint tuple, "" if none
  bool tuple_inout = false;
  std::vector<std::pair<std::string, Global>> results;  // assembly results
  std::vector<std::pair<std::string, Global>> vectors;  // global vector parameters
  std::ostringstream body;
  int indent = 1;
  int statements = 0;
};

struct Cg;

class ProgramGen {
 public:
  explicit ProgramGen(uint64_t seed) : rng_(seed) {}
  Generated generate();

 private:
  std::mt19937_64 rng_;
  SetData sets_;
  std::ostringstream funcs_;
  std::vector<Helper> helpers_;
  int names_ = 0;
  int main_block_ = 0;

  int pick(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  bool coin(double p) { return std::uniform_real_distribution<double>(0, 1)(rng_) < p; }
  double real(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  template <class T>
  const T& one_of(const std::vector<T>& v) {
    return v[static_cast<size_t>(pick(0, static_cast<int>(v.size()) - 1))];
  }
  std::string fresh(const char* prefix) { return prefix + std::to_string(names_++); }
  std::string number();
  std::string literal(Shape s);
  Shape random_shape();
  Global random_global(bool edge_map);

  // Expressions
  std::vector<Var> visible(const Fn& f) const;
  std::string index_below(const Fn& f, int n);
  std::string endpoint(const Fn& f);
  const std::vector<FieldSpec>& elem_fields(const Fn& f) const {
    return f.edge ? sets_.efields : sets_.vfields;
  }
  std::string member_for(const Fn& f, const Global& g);
  std::string fleaf(Fn& f, Shape s);
  std::string fexpr(Fn& f, Shape s, int depth);
  std::string fscalar(Fn& f, int depth);
  std::string fvector(Fn& f, Shape s, int depth);
  std::string fmatrix(Fn& f, Shape s, int depth);
  std::string big_product(Fn& f, Shape s, int depth);
  std::string denominator(Fn& f, int depth);
  bool helper_tail(Fn& f, const Helper& h, std::string& arg);
  std::string helper_args(Fn& f, const Helper& h, int depth, bool& ok);
  std::string helper_call(Fn& f, Shape s, int depth);
  std::string ileaf(Fn& f);
  std::string iexpr(Fn& f, int depth);
  std::string cond(Fn& f, int depth);

  // Statements
  void line(Fn& f, const std::string& s);
  void declare(Fn& f, const Var& v) { f.scopes.back().push_back(v); }
  void stmts(Fn& f, int count, int depth);
  void stmt(Fn& f, int depth);
  void decl_stmt(Fn& f);
  void assign_stmt(Fn& f);
  void if_stmt(Fn& f, int depth);
  void for_stmt(Fn& f, int depth);
  void result_write(Fn& f, const std::pair<std::string, Global>& r);
  void field_write(Fn& f);
  void multi_call(Fn& f);

  // Declarations
  void make_fields();
  void make_sets();
  void make_well_conditioned();
  void make_helper();
  std::string make_mapped(bool edge, bool endpoints, const std::vector<Global>& results,
                          const std::vector<Var>& partials, const std::vector<Global>& vectors,
                          bool reduce);
  std::pair<std::string, int> make_apply(bool edge);
  using Pool = std::vector<std::pair<std::string, Global>>;
  struct Step {
    std::ostringstream s;
    Pool pool, made;
    std::vector<std::string> scalars{"g_s"};
    std::vector<std::pair<std::string, std::string>> outs;  // name, type
  };
  std::string scalar_arg(Step& st) { return coin(0.5) ? number() : one_of(st.scalars); }
  std::string call_args(Step& st, const std::vector<Var>& partials,
                        const std::vector<std::string>& vectors);
  void map_site(Step& st, bool edge, const Pool& vectors);
  void system_stage(Step& st);
  std::string cg_text(const Cg& c);
  std::string branches(const Cg& c);
  void cg_stage(Step& st);
  void field_updates(Step& st);
  std::string step();
};

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

// An int that is a valid index below n: a literal or a loop variable bounded by n.
std::string ProgramGen::index_below(const Fn& f, int n) {
  std::vector<std::string> c;
  for (const Var& v : visible(f))
    if (v.bound > 0 && v.bound <= n) c.push_back(v.name);
  if (!c.empty() && coin(0.6)) return one_of(c);
  return std::to_string(pick(0, n - 1));
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
  switch (pick(0, 9)) {
    case 0:
    case 1:
    case 2: return "(" + e() + " + " + e() + ")";
    case 3:
    case 4: return "(" + e() + " - " + e() + ")";
    case 5:
    case 6: return "(" + e() + " * " + ileaf(f) + ")";
    case 7: return "mod(" + e() + ", 3)";
    default: return ileaf(f);
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
  } else if (k == 1) {
    v.kind = Kind::Bool;
    v.writable = true;
    line(f, "var " + v.name + " : bool = " + cond(f, 1) + ";");
  } else {
    v.shape = random_shape();
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

void ProgramGen::assign_stmt(Fn& f) {
  std::vector<Var> c;
  for (const Var& v : visible(f))
    if (v.writable) c.push_back(v);
  if (c.empty()) return decl_stmt(f);
  const Var v = one_of(c);
  if (v.kind == Kind::Int) return line(f, v.name + " = " + iexpr(f, 2) + ";");
  if (v.kind == Kind::Bool) return line(f, v.name + " = " + cond(f, 1) + ";");
  const int k = pick(0, 5);
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

// ---------------------------------------------------------------------------
// Declarations

void ProgramGen::make_fields() {
  auto make = [&](std::vector<FieldSpec>& out, const char* prefix) {
    out.push_back({std::string(prefix) + "s", Kind::Float, {}});
    const int extra = pick(1, 4);
    for (int i = 0; i < extra; ++i)
      out.push_back({std::string(prefix) + std::to_string(i), Kind::Float, random_shape()});
    if (coin(0.8)) out.push_back({std::string(prefix) + "pin", Kind::Bool, {}});
    if (coin(0.6)) out.push_back({std::string(prefix) + "k", Kind::Int, {}});
  };
  make(sets_.vfields, "a");
  make(sets_.efields, "b");
  // Some programs keep some float fields in binary32.
  if (coin(0.2))
    for (auto* fs : {&sets_.vfields, &sets_.efields})
      for (FieldSpec& fd : *fs) fd.single = fd.kind == Kind::Float && coin(0.5);
  // A vector field of the main block, so that CG finds a right-hand side.
  if (main_block_) sets_.vfields.push_back({"ax", Kind::Float, {main_block_, 0}});
}

void ProgramGen::make_sets() {
  sets_.verts = pick(1, 50);
  sets_.edges = pick(1, 50);
  sets_.arity = pick(1, 4);
  for (int e = 0; e < sets_.edges * sets_.arity; ++e)
    sets_.endpoints.push_back(pick(0, sets_.verts - 1));
  auto values = [&](const std::vector<FieldSpec>& fs, int n,
                    std::vector<std::vector<double>>& out) {
    for (const FieldSpec& fd : fs) {
      const int comps = fd.shape.scalar() ? 1 : fd.shape.rows * std::max(1, fd.shape.cols);
      std::vector<double> v;
      for (int i = 0; i < n * comps; ++i)
        v.push_back(fd.kind == Kind::Float ? real(-2.0, 2.0)
                    : fd.kind == Kind::Int ? pick(-3, 3)
                                           : (coin(0.3) ? 1.0 : 0.0));
      out.push_back(std::move(v));
    }
  };
  values(sets_.vfields, sets_.verts, sets_.vvalues);
  values(sets_.efields, sets_.edges, sets_.evalues);
}

// wcN(A): sin of every component plus 5 on the diagonal, diagonally dominant and therefore
// invertible, whatever A holds.
void ProgramGen::make_well_conditioned() {
  for (int n = 2; n <= 4; ++n) {
    const std::string t = "matrix[" + std::to_string(n) + "," + std::to_string(n) + "](float)";
    funcs_ << "func wc" << n << "(A : " << t << ") -> B : " << t << "\n"
           << "  for i in 0:" << n << "\n    for j in 0:" << n << "\n"
           << "      B(i, j) = sin(A(i, j));\n    end\n"
           << "    B(i, i) = B(i, i) + 5.0;\n  end\nend\n\n";
  }
}

void ProgramGen::make_helper() {
  using T = Helper::Takes;
  Helper h;
  h.name = fresh("h");
  Fn f;
  std::string sig;
  const int params = pick(1, 3);
  for (int i = 0; i < params; ++i) {
    Var p;
    p.name = fresh("p");
    p.shape = random_shape();
    h.params.push_back(p.shape);
    sig += (i ? ", " : "") + p.name + " : " + p.shape.type();
    declare(f, p);
  }
  const int k = pick(0, 9);
  h.takes = k < 5 ? T::Nothing : k < 7 ? T::Vertex : k < 9 ? T::Tuple : T::InoutVertex;
  if (h.takes == T::Vertex || h.takes == T::InoutVertex) {
    f.elem = "q";
    f.elem_inout = h.takes == T::InoutVertex;
    sig += f.elem_inout ? ", inout q : V" : ", q : V";
  }
  if (h.takes == T::Tuple) {
    f.tuple = "w";
    sig += ", w : (V * " + std::to_string(sets_.arity) + ")";
  }
  const int results = h.takes == T::InoutVertex ? 0 : coin(0.7) ? 1 : 2;
  std::vector<Var> rs;
  for (int i = 0; i < results; ++i) {
    Var r;
    r.name = fresh("r");
    r.shape = random_shape();
    r.writable = true;
    h.results.push_back(r.shape);
    rs.push_back(r);
  }
  stmts(f, pick(1, 4), 2);
  if (f.elem_inout) field_write(f);
  for (const Var& r : rs) {
    // Results start at zero: some are written only when a condition holds.
    if (coin(0.25)) {
      line(f, "if " + cond(f, 1));
      ++f.indent;
      line(f, r.name + " = " + fexpr(f, r.shape, 3) + ";");
      --f.indent;
      line(f, "end");
    } else {
      line(f, r.name + " = " + fexpr(f, r.shape, 3) + ";");
    }
    declare(f, r);
  }
  if (coin(0.4)) assign_stmt(f);
  std::string res;
  for (size_t i = 0; i < rs.size(); ++i)
    res += (i ? ", " : "") + rs[i].name + " : " + rs[i].shape.type();
  funcs_ << "func " << h.name << "(" << sig << ")"
         << (rs.empty()      ? ""
             : rs.size() > 1 ? " -> (" + res + ")"
                             : " -> " + res)
         << "\n"
         << f.body.str() << "end\n\n";
  helpers_.push_back(std::move(h));
}

std::string ProgramGen::make_mapped(bool edge, bool endpoints, const std::vector<Global>& results,
                                    const std::vector<Var>& partials,
                                    const std::vector<Global>& vectors, bool reduce) {
  Fn f;
  const std::string name = fresh("fm");
  std::string sig;
  for (Var p : partials) {
    p.name = fresh("s");
    sig += p.name + " : " + type_of(p.kind, p.shape) + ", ";
    declare(f, p);
  }
  for (const Global& g : vectors) {
    const std::string p = fresh("gv");
    sig += p + " : " + g.type() + ", ";
    f.vectors.emplace_back(p, g);
  }
  f.elem = edge ? "e" : "p";
  f.edge = edge;
  // Rarely the element is inout: the function updates fields as it assembles.
  f.elem_inout = coin(0.15);
  sig += f.elem_inout ? "inout " : "";
  sig += edge ? "e : E" : "p : V";
  if (edge && endpoints) {
    sig += ", v : (V * " + std::to_string(sets_.arity) + ")";
    f.tuple = "v";
  }
  std::string res;
  for (const Global& g : results) {
    f.results.emplace_back(fresh("R"), g);
    res += (res.empty() ? "" : ", ") + f.results.back().first + " : " + g.type();
  }
  stmts(f, pick(2, 6), 2);
  for (const auto& r : f.results) result_write(f, r);
  if (coin(0.3)) stmt(f, 1);
  funcs_ << "% " << (reduce ? "reduce +" : "no reduce: writes overwrite") << "\n"
         << "func " << name << "(" << sig << ")\n    -> (" << res << ")\n"
         << f.body.str() << "end\n\n";
  return name;
}

std::pair<std::string, int> ProgramGen::make_apply(bool edge) {
  Fn f;
  const std::string name = fresh("ap");
  std::string sig;
  const int partials = coin(0.5);
  if (partials) {
    Var p;
    p.name = fresh("s");
    sig += p.name + " : float, ";
    declare(f, p);
  }
  f.elem = edge ? "e" : "p";
  f.edge = edge;
  f.elem_inout = true;
  f.tuple_inout = edge && coin(0.15);
  sig += edge ? "inout e : E, " + std::string(f.tuple_inout ? "inout " : "") + "v : (V * " +
                    std::to_string(sets_.arity) + ")"
              : "inout p : V";
  if (edge) f.tuple = "v";
  stmts(f, pick(1, 4), 2);
  field_write(f);
  funcs_ << "func " << name << "(" << sig << ")\n" << f.body.str() << "end\n\n";
  return {name, partials};
}

std::string ProgramGen::call_args(Step& st, const std::vector<Var>& partials,
                                  const std::vector<std::string>& vectors) {
  std::string a;
  for (const Var& p : partials) {
    std::string v = p.kind == Kind::Int                   ? "(" + std::to_string(pick(-2, 4)) + ")"
                    : p.shape.scalar()                    ? scalar_arg(st)
                    : p.shape == Shape{3, 0} && coin(0.3) ? "k_v3"
                                                          : literal(p.shape);
    a += (a.empty() ? "" : ", ") + v;
  }
  for (const std::string& v : vectors) a += (a.empty() ? "" : ", ") + v;
  return a.empty() ? "" : "(" + a + ")";
}

void ProgramGen::map_site(Step& st, bool edge, const Pool& vectors) {
  std::vector<Global> rs;
  const int n = pick(1, 2);
  // Rarely an edge function without the endpoints: it can only write vectors over edges.
  const bool endpoints = !edge || coin(0.9);
  for (int i = 0; i < n; ++i) {
    rs.push_back(random_global(edge));
    if (!endpoints) rs.back() = {Global::Of::Edges, rs.back().block, 0};
  }
  const bool reduce = coin(0.7);
  // Partial arguments: mostly float scalars, also ints and small tensors.
  std::vector<Var> partials(static_cast<size_t>(pick(0, 2)));
  for (Var& p : partials) {
    const int k = pick(0, 9);
    if (k < 2) p.kind = Kind::Int;
    if (k >= 8) p.shape = random_shape();
  }
  std::vector<Global> types;
  std::vector<std::string> names;
  for (const auto& [name, g] : vectors) {
    types.push_back(g);
    names.push_back(name);
  }
  const std::string fm = make_mapped(edge, endpoints, rs, partials, types, reduce);
  std::string lhs;
  for (const Global& g : rs) {
    const std::string r = fresh("M");
    lhs += (lhs.empty() ? "" : ", ") + r;
    st.pool.push_back({r, g});
    st.made.push_back({r, g});
  }
  const std::string tail =
      std::string(" to ") + (edge ? "edges" : "verts") + (reduce ? " reduce +" : "");
  if (rs.size() > 1 || !coin(0.2)) {
    st.s << "  " << lhs << " = map " << fm << call_args(st, partials, names) << tail << ";\n";
    return;
  }
  // A site that runs twice in one call, after another site of the same function.
  const std::string k = fresh("k");
  st.s << "  var " << lhs << " = map " << fm << call_args(st, partials, names) << tail << ";\n"
       << "  for " << k << " in 0:2\n    " << lhs << " = " << lhs << " + (map " << fm
       << call_args(st, partials, names) << tail << ");\n  end\n";
}

// Statements over global vectors and matrices: products, linear combinations, inner products.
void ProgramGen::system_stage(Step& st) {
  const int n = pick(1, 5);
  for (int i = 0; i < n; ++i) {
    const auto [a, ga] = one_of(st.pool);
    Pool same, products;  // products: `a * x` or `a' * x`, with the type of the product
    for (const auto& p : st.pool) {
      if (p.second == ga) same.push_back(p);
      if (ga.matrix() && p.second == ga.cols())
        products.push_back({a + " * " + p.first, ga.rows()});
      if (ga.matrix() && p.second == ga.rows())
        products.push_back({a + "' * " + p.first, ga.cols()});
    }
    const std::string b = one_of(same).first;
    const std::string c = scalar_arg(st);
    const std::string name = fresh("y");
    Global out = ga;
    std::string e;
    if (!products.empty() && coin(0.6)) {
      const auto& [product, type] = one_of(products);
      e = product;
      out = type;
    } else if (!ga.matrix() && coin(0.35)) {
      const int k = pick(0, 2);
      e = k == 0 ? "dot(" + a + ", " + b + ")" : k == 1 ? a + "' * " + b : "norm(" + a + ")";
      st.s << "  " << name << " = " << e << ";\n";
      st.scalars.push_back(name);
      continue;
    } else {
      switch (pick(0, 4)) {
        case 0: e = c + " * " + a + " + " + b; break;
        case 1: e = a + " - " + c + " * " + b; break;
        case 2: e = "-" + a; break;
        case 3: e = a + " / 1.5"; break;
        default: e = ga.matrix() ? a + " + " + b : a + " .* " + b; break;
      }
    }
    st.s << "  " << name << " = " << e << ";\n";
    st.pool.push_back({name, out});
    st.made.push_back({name, out});
  }
}

// The names and variations of one CG-like loop.
struct Cg {
  std::string A, b;  // the operands as the loop names them
  std::string x, r, p, rs, it, Ap, alpha, rn, q, acc, flag, cnt, branchy;
  std::string other;  // a vector of x's type that the loop reads
  int iterations = 1;
  bool own_function = false, extra_vector = false, extra_scalar = false, extra_flag = false,
       extra_int = false;
  // An if: -1 none; on scalars 0 if/elif/else, 1 if, 2 if/else; 3 with a vector update and
  // a dot product in its branches.
  int if_form = -1;
  int error_at = -1;  // an error statement that fires at this iteration if the residual grew
};

// The loop and the declarations before it.
std::string ProgramGen::cg_text(const Cg& c) {
  std::ostringstream s;
  const std::string in = "  ", i2 = "    ", bound = std::to_string(c.iterations);
  // The scalars first or after the vectors: either way the set-up and the loop are one run
  // of statements (compiled as one trace), starting with scalar or with vector work.
  std::ostringstream scalars;
  if (!c.own_function) scalars << in << "var " << c.it << " = 0;\n";
  if (c.extra_scalar) scalars << in << "var " << c.acc << " = 0.0;\n";
  if (c.extra_flag) scalars << in << "var " << c.flag << " = true;\n";
  if (c.extra_int) scalars << in << "var " << c.cnt << " = 1;\n";
  if (c.if_form >= 0) scalars << in << "var " << c.branchy << " = 0.0;\n";
  const bool scalars_first = coin(0.5);
  if (scalars_first) s << scalars.str();
  s << in << "var " << c.x << " = " << (coin(0.5) ? "0.0 * " + c.b : c.b) << ";\n";
  s << in << "var " << c.r << " = " << c.b << " - " << c.A << " * " << c.x << ";\n";
  s << in << "var " << c.p << " = " << c.r << ";\n";
  s << in << "var " << c.rs << " = "
    << (coin(0.5) ? "dot(" + c.r + ", " + c.r + ")" : c.r + "' * " + c.r) << ";\n";
  if (c.extra_vector) s << in << "var " << c.q << " = " << c.x << ";\n";
  if (!scalars_first) s << scalars.str();
  const int form = c.extra_flag ? 0 : pick(1, 10);
  s << in << "while (" << c.it << " < " << bound << ")";
  if (form == 0) s << " and " << c.flag;
  if (form == 1) s << " and (norm(" << c.r << ") > 1.0e-12)";  // over vectors: interpreted
  if (form >= 2 && form <= 6) s << " and (" << c.rs << " > 1.0e-20)";
  s << "\n";
  s << i2 << c.Ap << " = " << c.A << " * " << c.p << ";\n";
  s << i2 << c.alpha << " = " << c.rs << " / "
    << (coin(0.5) ? "dot(" + c.p + ", " + c.Ap + ")" : "(" + c.p + "' * " + c.Ap + ")") << ";\n";
  s << i2 << c.x << " = " << c.x << " + " << c.alpha << " * " << c.p << ";\n";
  s << i2 << c.r << " = " << c.r << " - " << c.alpha << " * " << c.Ap << ";\n";
  if (c.extra_vector)
    s << i2 << c.q << " = 0.5 * " << c.q << " - " << c.alpha << " * " << c.other << ";\n";
  switch (pick(0, 2)) {
    case 0: s << i2 << c.rn << " = " << c.r << "' * " << c.r << ";\n"; break;
    case 1: s << i2 << c.rn << " = dot(" << c.r << ", " << c.r << ");\n"; break;
    default: s << i2 << c.rn << " = norm(" << c.r << ") * norm(" << c.r << ");\n";
  }
  if (c.extra_scalar) {
    const std::string acc = i2 + c.acc + " = " + c.acc;
    switch (pick(0, 4)) {
      case 0: s << acc << " + max(" << c.alpha << ", 0.0);\n"; break;
      case 1: s << acc << " + g_s * " << c.alpha << ";\n"; break;
      case 2: s << acc << " * k_s + " << c.rn << ";\n"; break;
      // A dot product after a scalar statement: its pass moves up to the x and r updates.
      case 3: s << acc << " + 1.0e-3 * (" << c.x << "' * " << c.x << ");\n"; break;
      default: s << acc << " + sqrt(abs(" << c.alpha << "));\n";
    }
  }
  if (c.extra_flag) s << i2 << c.flag << " = " << c.rn << " < " << c.rs << ";\n";
  if (c.extra_int) s << i2 << c.cnt << " = " << c.cnt << " * 2 - " << c.it << ";\n";
  s << branches(c);
  s << i2 << c.p << " = " << c.r << " + (" << c.rn << " / " << c.rs << ") * " << c.p << ";\n";
  s << i2 << c.rs << " = " << c.rn << ";\n";
  s << i2 << c.it << " = " << c.it << " + 1;\n";
  s << in << "end\n";
  return s.str();
}

// The loop's ifs on scalars: one whose branches update a scalar, and an error statement.
std::string ProgramGen::branches(const Cg& c) {
  std::ostringstream s;
  const std::string i2 = "    ", i3 = "      ", set = i3 + c.branchy + " = ";
  if (c.if_form == 3) {
    s << i2 << "if " << c.rn << " > " << c.rs << "\n"
      << set << c.branchy << " + " << c.alpha << ";\n"
      << i3 << c.x << " = " << c.x << " - (0.25 * " << c.alpha << ") * " << c.p << ";\n"
      << i2 << "else\n"
      << set << c.branchy << " - dot(" << c.r << ", " << c.r << ");\n"
      << i2 << "end\n";
  } else if (c.if_form >= 0) {
    s << i2 << "if " << c.rn << " > " << c.rs << "\n"
      << set << c.branchy << " + " << c.alpha << ";\n";
    if (c.if_form == 0)
      s << i2 << "elif " << c.it << " == 1\n" << set << "0.5 * " << c.branchy << " - 1.0;\n";
    if (c.if_form != 1) s << i2 << "else\n" << set << c.branchy << " * k_s;\n";
    s << i2 << "end\n";
  }
  if (c.error_at >= 0)
    s << i2 << "if (" << c.it << " == " << c.error_at << ") and (" << c.rn << " > " << c.rs << ")\n"
      << i3 << "error \"the residual grew at iteration \", " << c.it << ", \": \", " << c.rn
      << ";\n"
      << i2 << "end\n";
  return s.str();
}

// A conjugate-gradient-like loop over a matrix and a vector of the same blocks, in the step
// itself or in a function of its own.
void ProgramGen::cg_stage(Step& st) {
  if (!coin(0.7)) return;
  std::vector<std::pair<std::string, std::string>> pairs;  // matrix, right-hand side
  Global vt;
  for (const auto& [m, gm] : st.pool)
    if (gm.square())
      for (const auto& [v, gv] : st.pool)
        if (gv == gm.cols()) pairs.push_back({m, v});
  if (pairs.empty()) return;
  const auto [A, b] = one_of(pairs);
  for (const auto& [v, gv] : st.pool)
    if (v == b) vt = gv;
  Cg c;
  c.own_function = coin(0.3);
  c.A = c.own_function ? "A" : A;
  c.b = c.own_function ? "b" : b;
  for (auto [name, prefix] : {std::pair{&c.x, "cx"},
                              {&c.r, "cr"},
                              {&c.p, "cp"},
                              {&c.rs, "crs"},
                              {&c.it, "cit"},
                              {&c.Ap, "cAp"},
                              {&c.alpha, "calpha"},
                              {&c.rn, "crn"},
                              {&c.q, "cq"},
                              {&c.acc, "cacc"},
                              {&c.flag, "cflag"},
                              {&c.cnt, "ccnt"},
                              {&c.branchy, "cif"}})
    *name = fresh(prefix);
  c.iterations = pick(1, 8);
  c.extra_vector = coin(0.4);
  c.extra_scalar = coin(0.4);
  c.extra_flag = coin(0.25);
  c.extra_int = coin(0.25);
  c.if_form = coin(0.4) ? pick(0, 3) : -1;
  c.error_at = coin(0.15) ? pick(0, c.iterations - 1) : -1;
  // Another vector of the same type, read in the loop (a field view stays interpreted).
  std::vector<std::string> others;
  const bool views = coin(0.2);
  for (const auto& [v, gv] : st.pool) {
    const bool view = v.find('.') != std::string::npos;
    if (gv == vt && (view ? views : !c.own_function)) others.push_back(v);
  }
  c.other = others.empty() || !coin(0.5) ? c.Ap : one_of(others);
  const std::string loop = cg_text(c);
  auto out = [&](const std::string& type, const std::string& value) {
    st.outs.push_back({fresh("o"), type});
    st.s << "  " << st.outs.back().first << " = " << value << ";\n";
  };
  if (c.own_function) {
    const std::string fn = fresh("cg");
    funcs_ << "func " << fn << "(A : " << Global{Global::Of::Matrix, vt.block, vt.block}.type()
           << ", b : " << vt.type() << ")\n    -> (" << c.x << "out : " << vt.type() << ", " << c.it
           << " : int, " << c.rs << "out : float)\n"
           << loop << "  " << c.x << "out = " << c.x << ";\n  " << c.rs << "out = " << c.rs
           << ";\nend\n\n";
    st.s << "  " << c.x << ", " << c.it << ", " << c.rs << " = " << fn << "(" << A << ", " << b
         << ");\n";
  } else {
    st.s << loop;
    if (c.extra_scalar) st.scalars.push_back(c.acc);
    if (c.if_form >= 0) st.scalars.push_back(c.branchy);
    if (c.extra_vector) st.made.push_back({c.q, vt});
    if (c.extra_flag) out("bool", c.flag);
    if (c.extra_int) out("int", c.cnt);
  }
  st.pool.push_back({c.x, vt});
  st.made.push_back({c.x, vt});
  st.scalars.push_back(c.rs);
  out("int", c.it);
}

// Fields updated from system vectors, so that the next call starts elsewhere.
void ProgramGen::field_updates(Step& st) {
  for (const bool edge : {false, true})
    for (const FieldSpec& fd : edge ? sets_.efields : sets_.vfields) {
      if (fd.kind != Kind::Float || fd.shape.matrix() || !coin(0.4)) continue;
      const Global::Of of = edge ? Global::Of::Edges : Global::Of::Verts;
      std::vector<std::string> c;
      for (const auto& [v, g] : st.pool)
        if (g.of == of && g.block == fd.shape.rows) c.push_back(v);
      if (c.empty()) continue;
      const std::string f = (edge ? "edges." : "verts.") + fd.name;
      st.s << "  " << f << " = " << f << " + 0.0625 * " << one_of(c) << ";\n";
    }
}

// The exported step: applies, maps, system-level statements over their results, maybe a CG
// loop, field updates; it returns every system value it made.
std::string ProgramGen::step() {
  Step st;
  if (coin(0.6)) {
    const auto [ap, partials] = make_apply(false);
    st.s << "  apply " << ap << call_args(st, std::vector<Var>(partials), {}) << " to verts;\n";
  }
  if (coin(0.4)) {
    const auto [ap, partials] = make_apply(true);
    st.s << "  apply " << ap << call_args(st, std::vector<Var>(partials), {}) << " to edges;\n";
  }
  for (const FieldSpec& fd : sets_.vfields)
    if (fd.kind == Kind::Float && !fd.shape.matrix())
      st.pool.push_back({"verts." + fd.name, {Global::Of::Verts, fd.shape.rows}});
  for (const FieldSpec& fd : sets_.efields)
    if (fd.kind == Kind::Float && !fd.shape.matrix() && coin(0.5))
      st.pool.push_back({"edges." + fd.name, {Global::Of::Edges, fd.shape.rows}});
  const int edge_maps = pick(1, 2);
  for (int i = 0; i < edge_maps; ++i) map_site(st, true, {});
  if (coin(0.6)) map_site(st, false, {});
  system_stage(st);
  Pool vectors;  // a late map reads one of them at its members
  for (const auto& p : st.pool)
    if (p.second.of == Global::Of::Verts) vectors.push_back(p);
  if (!vectors.empty() && coin(0.5)) map_site(st, coin(0.5), {one_of(vectors)});
  cg_stage(st);
  field_updates(st);
  // The program writes the extern: the next call's sites must read the new value.
  if (coin(0.3)) st.s << "  g_s = 0.5 * g_s + " << number() << ";\n";
  for (const auto& [name, g] : st.made) {
    st.outs.push_back({fresh("o"), g.type()});
    st.s << "  " << st.outs.back().first << " = " << name << ";\n";
  }
  for (size_t i = 1; i < st.scalars.size(); ++i) {
    st.outs.push_back({fresh("o"), "float"});
    st.s << "  " << st.outs.back().first << " = " << st.scalars[i] << ";\n";
  }
  std::string header = "export func step()";
  if (!st.outs.empty()) {
    header += " -> (";
    for (size_t i = 0; i < st.outs.size(); ++i)
      header += (i ? ", " : "") + st.outs[i].first + " : " + st.outs[i].second;
    header += ")";
  }
  return header + "\n" + st.s.str() + "end\n";
}

Generated ProgramGen::generate() {
  main_block_ = one_of(std::vector<int>{0, 0, 2, 3, 4});
  make_fields();
  make_sets();
  std::ostringstream decls;
  auto element = [&](const char* name, const std::vector<FieldSpec>& fs) {
    decls << "element " << name << "\n";
    for (const FieldSpec& fd : fs)
      decls << "  " << fd.name << " : " << type_of(fd.kind, fd.shape) << ";\n";
    decls << "end\n\n";
  };
  element("V", sets_.vfields);
  element("E", sets_.efields);
  decls << "extern verts : set{V};\n";
  if (coin(0.5)) {
    decls << "extern edges : set{E}(verts * " << sets_.arity << ");\n";
  } else {
    decls << "extern edges : set{E}(";
    for (int i = 0; i < sets_.arity; ++i) decls << (i ? ", " : "") << "verts";
    decls << ");\n";
  }
  decls << "extern g_s : float;\n\n";
  decls << "const k_s = " << number() << ";\n";
  decls << "const k_v3 = " << literal({3, 0}) << ";\n";
  decls << "const k_m22 = " << literal({2, 2}) << ";\n\n";
  make_well_conditioned();
  const int helpers = pick(0, 3);
  for (int i = 0; i < helpers; ++i) make_helper();
  const std::string st = step();
  Generated g;
  g.text = decls.str() + funcs_.str() + st;
  g.sets = sets_;
  g.g_s = real(-1.0, 1.0);
  g.float32 = coin(0.15);
  g.host_seed = rng_();
  g.topology_change = coin(0.3);
  return g;
}

// ---------------------------------------------------------------------------
// Running a program through both executors

runtime::FieldType field_type(const FieldSpec& fd) {
  using runtime::ComponentKind;
  runtime::FieldType t;
  t.kind = fd.kind == Kind::Float ? ComponentKind::Float
           : fd.kind == Kind::Int ? ComponentKind::Int
                                  : ComponentKind::Bool;
  t.single = fd.single;
  if (fd.shape.rows) t.dims.push_back(fd.shape.rows);
  if (fd.shape.cols) t.dims.push_back(fd.shape.cols);
  return t;
}

void fill_fields(runtime::Set& set, const std::vector<FieldSpec>& fs,
                 const std::vector<std::vector<double>>& values) {
  for (size_t i = 0; i < fs.size(); ++i) {
    const int f = set.add_field(fs[i].name, field_type(fs[i]));
    const std::vector<double>& v = values[i];
    for (size_t k = 0; k < v.size(); ++k) {
      switch (fs[i].kind) {
        case Kind::Float:
          if (fs[i].single)
            set.field(f).data<float>()[k] = static_cast<float>(v[k]);
          else
            set.field(f).data<double>()[k] = v[k];
          break;
        case Kind::Int: set.field(f).data<int32_t>()[k] = static_cast<int32_t>(v[k]); break;
        case Kind::Bool: set.field(f).data<bool>()[k] = v[k] != 0.0; break;
      }
    }
  }
}

struct World {
  runtime::Set verts{"verts"};
  std::unique_ptr<runtime::Set> edges;

  explicit World(const SetData& d) {
    verts.add_many(d.verts);
    edges = std::make_unique<runtime::Set>(
        "edges", std::vector<const runtime::Set*>(static_cast<size_t>(d.arity), &verts));
    edges->add_edges(d.endpoints);
    fill_fields(verts, d.vfields, d.vvalues);
    fill_fields(*edges, d.efields, d.evalues);
  }
};

// What the host does between calls, the same to both worlds: it rewrites some field
// components (flipping pins among them) before the second call and, in some programs, adds
// vertices and edges before the third.
void host_changes(World& w, const Generated& g, int call) {
  std::mt19937_64 rng(g.host_seed + static_cast<uint64_t>(call));
  auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  auto rewrite = [&](runtime::Set& set, int element) {
    if (set.field_count() == 0) return;
    runtime::Field& f = set.field(pick(0, set.field_count() - 1));
    const size_t k = static_cast<size_t>(element) * f.components() +
                     static_cast<size_t>(pick(0, static_cast<int>(f.components()) - 1));
    const double v = std::uniform_real_distribution<double>(-2.0, 2.0)(rng);
    switch (f.type().kind) {
      case runtime::ComponentKind::Float:
        if (f.type().single)
          f.data<float>()[k] = static_cast<float>(v);
        else
          f.data<double>()[k] = v;
        break;
      case runtime::ComponentKind::Int: f.data<int32_t>()[k] = pick(-3, 3); break;
      case runtime::ComponentKind::Bool: f.data<bool>()[k] = !f.data<bool>()[k]; break;
      default: break;
    }
  };
  if (call == 1) {
    for (int i = 0; i < 4; ++i) {
      rewrite(w.verts, pick(0, w.verts.size() - 1));
      rewrite(*w.edges, pick(0, w.edges->size() - 1));
    }
  }
  if (call == 2 && g.topology_change) {
    const int added = pick(1, 3);
    for (int i = 0; i < added; ++i) rewrite(w.verts, w.verts.add());
    for (int i = 0; i < added; ++i) {
      std::vector<int32_t> ends;
      for (int k = 0; k < g.sets.arity; ++k) ends.push_back(pick(0, w.verts.size() - 1));
      rewrite(*w.edges, w.edges->add(ends));
    }
  }
}

struct Runner {
  World world;
  std::unique_ptr<Engine> engine;
  Runner(const std::shared_ptr<const CompiledProgram>& program, const Generated& g,
         ExecutorKind kind)
      : world(g.sets) {
    EngineOptions o;
    o.executor = kind;
    o.jit.threshold = 0;
    o.float32 = g.float32;
    engine = std::make_unique<Engine>(program, o);
    engine->bind_set(*program->find_extern("verts"), world.verts);
    engine->bind_set(*program->find_extern("edges"), *world.edges);
    engine->set_global(*program->find_extern("g_s"), Value::of_float(g.g_s));
  }
  // The results, or the run-time error's text.
  std::vector<Value> call(const std::string& name, std::string& error) {
    try {
      return engine->call(*engine->compiled().find_func(name), {});
    } catch (const interp::RuntimeError& e) {
      error = e.render();
    }
    return {};
  }
};

// Bit-for-bit equality of doubles; two NaNs count as equal (their payloads are not part of
// the arithmetic contract), and so do +0 and -0 (where the JIT folds a product by a zero,
// docs/jit.md). Where the interpreter has a NaN the JIT may have a number: a matrix on a
// specialised pattern leaves out zero blocks, whose 0 * inf or 0 * NaN terms are the
// interpreter's only NaN (docs/jit.md); the reverse, a NaN only in the JIT's result, is an
// error. Returns "" or the first difference.
std::string differ(const double* a, const double* b, size_t n, const std::string& what, int* nans) {
  for (size_t i = 0; i < n; ++i) {
    if (std::memcmp(&a[i], &b[i], sizeof(double)) == 0) continue;
    if (a[i] == 0.0 && b[i] == 0.0) continue;
    if (std::isnan(a[i])) {
      ++*nans;
      continue;
    }
    char buf[160];
    std::snprintf(buf, sizeof buf, "[%zu]: interpreter %.17g, jit %.17g", i, a[i], b[i]);
    return what + buf;
  }
  return "";
}

template <class T>
std::string differ_exact(const T* a, const T* b, size_t n, const std::string& what) {
  for (size_t i = 0; i < n; ++i)
    if (a[i] != b[i])
      return what + "[" + std::to_string(i) + "]: interpreter " + std::to_string(a[i]) + ", jit " +
             std::to_string(b[i]);
  return "";
}

std::string differ(const Value& a, const Value& b, const std::string& what, int* nans) {
  if (a.kind() != b.kind()) return what + ": values of different kinds";
  switch (a.kind()) {
    case Value::Kind::Float: {
      const double x = a.as_float(), y = b.as_float();
      return differ(&x, &y, 1, what, nans);
    }
    case Value::Kind::Int:
      return a.as_int() == b.as_int() ? ""
                                      : what + ": interpreter " + std::to_string(a.as_int()) +
                                            ", jit " + std::to_string(b.as_int());
    case Value::Kind::Bool: return a.as_bool() == b.as_bool() ? "" : what + ": booleans differ";
    case Value::Kind::Matrix: {
      const runtime::SystemMatrix& x = *a.matrix();
      const runtime::SystemMatrix& y = *b.matrix();
      if (x.pattern().col_idx() == y.pattern().col_idx() &&
          x.pattern().row_ptr() == y.pattern().row_ptr())
        return differ(x.values(), y.values(), x.value_count(), what, nans);
      // The JIT's result on a specialised pattern: its blocks are blocks of the interpreter's,
      // equal, and the interpreter's others hold only zeros.
      if (y.pattern().nnz() > x.pattern().nnz() || x.block_size() != y.block_size())
        return what + ": different patterns";
      const int bs = x.block_size();
      const std::vector<double> zero(static_cast<size_t>(bs), 0.0);
      int64_t found = 0;
      for (int r = 0; r < x.rows(); ++r)
        for (int32_t k = x.pattern().row_ptr()[r]; k < x.pattern().row_ptr()[r + 1]; ++k) {
          const int32_t at = y.pattern().find(r, x.pattern().col_idx()[k]);
          const double* in = x.values() + static_cast<size_t>(k) * bs;
          const double* jit = at >= 0 ? y.values() + static_cast<size_t>(at) * bs : zero.data();
          found += at >= 0;
          const std::string d = differ(in, jit, static_cast<size_t>(bs),
                                       what + " block (" + std::to_string(r) + ", " +
                                           std::to_string(x.pattern().col_idx()[k]) + ")",
                                       nans);
          if (!d.empty()) return d;
        }
      return found == y.pattern().nnz() ? "" : what + ": blocks outside the interpreter's pattern";
    }
    default: break;
  }
  if (!a.is_tensor()) return "";
  const runtime::Tensor& x = a.tensor();
  const runtime::Tensor& y = b.tensor();
  if (x.size() != y.size()) return what + ": different sizes";
  switch (x.kind()) {
    case runtime::ComponentKind::Float: return differ(x.floats(), y.floats(), x.size(), what, nans);
    case runtime::ComponentKind::Int: return differ_exact(x.ints(), y.ints(), x.size(), what);
    case runtime::ComponentKind::Bool: return differ_exact(x.bools(), y.bools(), x.size(), what);
    default: return "";
  }
}

std::string differ(const runtime::Set& a, const runtime::Set& b, int* nans) {
  for (int f = 0; f < a.field_count(); ++f) {
    const runtime::Field& x = a.field(f);
    const runtime::Field& y = b.field(f);
    const size_t n = static_cast<size_t>(a.size()) * x.components();
    const std::string what = a.name() + "." + x.name();
    std::string d;
    switch (x.type().kind) {
      case runtime::ComponentKind::Float:
        if (x.type().single) {
          const std::vector<double> a(x.data<float>(), x.data<float>() + n),
              b(y.data<float>(), y.data<float>() + n);
          d = differ(a.data(), b.data(), n, what, nans);
        } else {
          d = differ(x.data<double>(), y.data<double>(), n, what, nans);
        }
        break;
      case runtime::ComponentKind::Int:
        d = differ_exact(x.data<int32_t>(), y.data<int32_t>(), n, what);
        break;
      case runtime::ComponentKind::Bool:
        d = differ_exact(x.data<bool>(), y.data<bool>(), n, what);
        break;
      default: break;
    }
    if (!d.empty()) return d;
  }
  return "";
}

// What the JIT did with a program's sites and loops, from print_jit_stats.
struct Tally {
  int programs = 0, runtime_errors = 0, nans = 0;
  int sites_compiled = 0, sites_interpreted = 0, loops_compiled = 0, loops_interpreted = 0;
  int runs_compiled = 0, runs_interpreted = 0;  // runs of statements (a loop and its set-up)
  int statements_compiled = 0;                  // system statements compiled alone
  std::map<std::string, int> reasons;

  void add(const std::string& stats) {
    std::istringstream in(stats);
    std::string l;
    static const std::regex line_no(" \\(lines? [0-9]+(-[0-9]+)?\\)");
    static const std::regex quoted("'[A-Za-z0-9_]+'");
    while (std::getline(in, l)) {
      if (l.rfind("      key:", 0) == 0 || l.rfind("jit traces:", 0) == 0 ||
          l.rfind("  site ", 0) == 0)
        continue;
      const bool loop = l.rfind("  while (line", 0) == 0;
      const bool run = l.rfind("  statements (lines", 0) == 0;
      const bool alone = l.rfind("  statement (line", 0) == 0;  // listed when compiled
      if (l.size() >= 9 && l.compare(l.size() - 9, 9, " compiled") == 0) {
        ++(alone  ? statements_compiled
           : run  ? runs_compiled
           : loop ? loops_compiled
                  : sites_compiled);
        continue;
      }
      size_t at = l.find("interpreted: ");
      if (at == std::string::npos) at = l.find("no code generator");
      if (at == std::string::npos) continue;
      ++(run ? runs_interpreted : loop ? loops_interpreted : sites_interpreted);
      std::string why = std::regex_replace(l.substr(at), line_no, "");
      why = std::regex_replace(why, quoted, "'x'");
      ++reasons[(run ? "run: " : loop ? "loop: " : "site: ") + why];
    }
  }
};

long env_long(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::strtol(v, nullptr, 10) : fallback;
}

// Runs one generated program through both executors for a few calls of `step`. Returns ""
// or a report of the first difference.
std::string check_program(uint64_t seed, Tally& tally) {
  const Generated g = ProgramGen(seed).generate();
  const auto program = CompiledProgram::from_source("random.sim", g.text);
  if (!program->ok())
    return "the generator made a program that does not check (a generator bug):\n" + g.text + "\n" +
           program->compilation()->diagnostics.render_all();
  if (env_long("SIMIT_RANDOM_PRINT", 0))
    std::printf("--- seed %llu ---\n%s", static_cast<unsigned long long>(seed), g.text.c_str());
  Runner in(program, g, ExecutorKind::Interpreter), jit(program, g, ExecutorKind::Jit);
  ++tally.programs;
  std::string diff;
  for (int call = 0; call < 3 && diff.empty(); ++call) {
    std::string in_error, jit_error;
    host_changes(in.world, g, call);
    host_changes(jit.world, g, call);
    const std::vector<Value> a = in.call("step", in_error), b = jit.call("step", jit_error);
    const std::string at = "call " + std::to_string(call + 1) + ": ";
    if (in_error != jit_error) {
      diff = at + "run-time errors differ:\n  interpreter: " + in_error + "\n  jit: " + jit_error;
      break;
    }
    if (!in_error.empty()) {
      ++tally.runtime_errors;
      break;
    }
    if (a.size() != b.size()) diff = at + "different result counts";
    for (size_t i = 0; i < a.size() && diff.empty(); ++i)
      diff = differ(a[i], b[i], "result " + std::to_string(i), &tally.nans);
    if (diff.empty()) diff = differ(in.world.verts, jit.world.verts, &tally.nans);
    if (diff.empty()) diff = differ(*in.world.edges, *jit.world.edges, &tally.nans);
    if (!diff.empty()) diff = at + diff;
  }
  std::ostringstream stats;
  jit.engine->print_jit_stats(stats);
  tally.add(stats.str());
  if (env_long("SIMIT_RANDOM_PRINT", 0)) std::printf("%s", stats.str().c_str());
  if (diff.empty()) return "";
  return "seed " + std::to_string(seed) + ": " + diff + "\n--- program ---\n" + g.text +
         "--- jit ---\n" + stats.str();
}

TEST(RandomPrograms, TheJitComputesTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const long count = env_long("SIMIT_RANDOM_PROGRAMS", kDefaultPrograms);
  const uint64_t first = static_cast<uint64_t>(env_long("SIMIT_RANDOM_SEED", 1));
  Tally tally;
  int failures = 0;
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i < count && failures < 3; ++i) {
    const std::string report = check_program(first + static_cast<uint64_t>(i), tally);
    if (!report.empty()) {
      ++failures;
      ADD_FAILURE() << report;
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%d programs from seed %llu in %.1f s: %d runtime errors (alike), %d NaNs alike\n",
              tally.programs, static_cast<unsigned long long>(first), seconds, tally.runtime_errors,
              tally.nans);
  std::printf(
      "map/apply sites: %d compiled, %d interpreted; while loops alone: %d compiled, %d "
      "interpreted; runs of statements: %d compiled, %d interpreted; statements alone: %d "
      "compiled\nwhy interpreted:\n",
      tally.sites_compiled, tally.sites_interpreted, tally.loops_compiled, tally.loops_interpreted,
      tally.runs_compiled, tally.runs_interpreted, tally.statements_compiled);
  std::vector<std::pair<int, std::string>> reasons;
  for (const auto& [why, n] : tally.reasons) reasons.push_back({n, why});
  std::sort(reasons.rbegin(), reasons.rend());
  for (const auto& [n, why] : reasons) std::printf("  %5d  %s\n", n, why.c_str());
  // Not vacuous: most sites and loops ran compiled.
  if (tally.programs < 50) return;  // a few seeds replayed: too few to judge the mix
  EXPECT_GT(tally.sites_compiled, 2 * tally.sites_interpreted);
  // A loop compiles alone or in its run; a run that does not compile leaves its loop to be
  // offered alone (most runs stop at a field read or a float32 program).
  EXPECT_GT(tally.loops_compiled + tally.runs_compiled, 2 * tally.loops_interpreted);
  EXPECT_GT(tally.runs_compiled, tally.programs / 4);
  EXPECT_LT(tally.runtime_errors, tally.programs / 10 + 1);
}
}  // namespace
}  // namespace simit::jit
