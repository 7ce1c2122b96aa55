// The random-program generator of random_program_test.cpp: Simit programs (element functions,
// maps, applies, system statements, CG-like loops) and the sets they run on, made from a seed.
#pragma once

#include <cstdint>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace simit::jit::random_programs {

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

inline std::string type_of(Kind k, Shape s) {
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
  int chain_depth = 0;  // the depth of its chain of helpers, 0 if none
};

// The program of one seed, with its sets.
Generated generate_program(uint64_t seed);

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
  // Some programs divide by int leaves that may be zero (no guard): both executors must then
  // stop with the same error.
  bool raw_divisions_ = false;
  int chain_depth_ = 0;

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
  std::string loop_index(const Var& v, int n);
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
  std::string int_divisor(Fn& f);
  std::string cond(Fn& f, int depth);

  // Statements
  void line(Fn& f, const std::string& s);
  void declare(Fn& f, const Var& v) { f.scopes.back().push_back(v); }
  void stmts(Fn& f, int count, int depth);
  void stmt(Fn& f, int depth);
  void decl_stmt(Fn& f);
  void broadcast_decl(Fn& f, Var v);
  void guarded_division(Fn& f, const Var& v);
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
  void make_chain();
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

}  // namespace simit::jit::random_programs
