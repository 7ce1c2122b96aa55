// The random-program generator's declarations: fields, sets, helpers, element functions,
// maps and applies, and the exported step with its system statements and CG-like loops.
#include <algorithm>

#include "jit/tunables.h"
#include "random_program_gen.h"

namespace simit::jit::random_programs {

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
  // Some programs run on no vertices (and so no edges), some on no edges: their maps, products
  // and loops run over empty vectors and matrices without rows or blocks.
  const int empty = pick(0, 99);
  sets_.verts = empty < 4 ? 0 : pick(1, 50);
  sets_.edges = empty < 8 ? 0 : pick(1, 50);
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

// A chain of scalar helpers, each calling the next: mostly 28 to 40 deep, sometimes just within
// or just past the JIT's inline depth (kMaxInlineDepth), where a site stays interpreted; either
// way it computes the interpreter's values. Its head is a helper like the others.
void ProgramGen::make_chain() {
  const int depth =
      coin(0.7) ? pick(28, 40) : pick(std::max(1, kMaxInlineDepth - 3), kMaxInlineDepth + 3);
  const std::string base = fresh("hc") + "_";
  auto name = [&](int i) { return base + std::to_string(i); };
  chain_depth_ = depth;
  funcs_ << "func " << name(depth - 1) << "(x : float) -> y : float\n  y = sin(x);\nend\n\n";
  for (int i = depth - 2; i >= 0; --i)
    funcs_ << "func " << name(i) << "(x : float) -> y : float\n  y = 0.5 * " << name(i + 1)
           << "(x + " << number() << ") + " << number() << ";\nend\n\n";
  Helper h;
  h.name = name(0);
  h.params = {Shape{}};
  h.results = {Shape{}};
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
    // Now and then a product into its own operand (`y = A * y`), which the JIT must not
    // compute in place.
    std::vector<std::string> operands;
    for (const auto& p : st.pool)
      if (ga.square() && p.second == ga.cols()) operands.push_back(p.first);
    if (!operands.empty() && coin(0.12)) {
      st.s << "  var " << name << " = " << one_of(operands) << ";\n  " << name << " = " << a
           << " * " << name << ";\n";
      st.pool.push_back({name, ga.cols()});
      st.made.push_back({name, ga.cols()});
      continue;
    }
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
  // The extra vector: a step along another vector, or a product into its own operand.
  if (c.extra_vector && coin(0.7))
    s << i2 << c.q << " = 0.5 * " << c.q << " - " << c.alpha << " * " << c.other << ";\n";
  else if (c.extra_vector)
    s << i2 << c.q << " = " << c.A << " * " << c.q << ";\n";
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
  if (c.extra_int) {
    // Integer arithmetic among the loop's scalars, with mod and `/` of negative operands; in a
    // program with raw divisions, a divisor that reaches zero at the second iteration (both
    // executors stop there with the same error).
    const std::string set = i2 + c.cnt + " = ";
    switch (raw_divisions_ ? pick(0, 3) : pick(0, 2)) {
      case 0: s << set << c.cnt << " * 2 - " << c.it << ";\n"; break;
      case 1: s << set << "mod(" << c.cnt << " * 3 - " << c.it << ", 5) - 2;\n"; break;
      case 2:
        s << set << "(" << c.cnt << " - 3 * " << c.it << ") / (-2) + " << c.it << ";\n";
        break;
      default: s << set << "mod(" << c.cnt << " + 5, " << c.it << " - 1);\n";
    }
  }
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
      // A vertex field multiplied in place by a square matrix of its blocks (`verts.f = M *
      // verts.f`), or a step along a vector.
      std::vector<std::string> ms;
      for (const auto& [m, g] : st.pool)
        if (!edge && g.square() && g.block == fd.shape.rows) ms.push_back(m);
      if (!ms.empty() && coin(0.15)) {
        st.s << "  " << f << " = " << one_of(ms) << " * " << f << ";\n";
        continue;
      }
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
  raw_divisions_ = coin(0.03);
  // A chain of helpers comes first, so that the others may call it too.
  if (coin(0.08)) make_chain();
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
  g.chain_depth = chain_depth_;
  return g;
}

Generated generate_program(uint64_t seed) { return ProgramGen(seed).generate(); }

}  // namespace simit::jit::random_programs
