// The reference interpreter: executes a checked program by walking its typed AST. Every
// variable lives in a frame slot that the checker assigned, so nothing is looked up by name
// while running. Run-time errors stop the run with a RuntimeError (file:line:col and the
// call stack).
#pragma once

#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

#include "frontend/ast.h"
#include "interp/assembly_plan.h"
#include "interp/exec_state.h"
#include "interp/hook.h"
#include "interp/inspect.h"
#include "interp/options.h"
#include "interp/runtime_error.h"
#include "interp/set_binding.h"
#include "interp/value.h"
#include "runtime/system_matrix.h"

namespace simit::interp {

// Where a write lands: a whole variable, or a component / block inside its tensor.
struct Place {
  Value* root = nullptr;
  bool whole = true;
  size_t offset = 0;  // first component of the addressed part (when not whole)
  Shape shape;        // shape of the addressed part: scalar for one component
  // A set field (root is null): the components [offset, offset + shape.size()) of the
  // field's array, read and written there directly. `whole` is the whole field (element
  // < 0, from `S.f`); otherwise `element` is the element addressed (from `e.f`, `S.f(e)`).
  runtime::Set* field_set = nullptr;
  int field = -1;
  int element = -1;
  // A block of a system matrix being assembled (root is the matrix value).
  int32_t matrix_position = -1;
  bool accumulate = false;  // `reduce +`: the write adds
};

class Interpreter final : public ExecState {
 public:
  // `program` must have checked without diagnostics and must outlive the interpreter.
  // Global constants are evaluated here; externs start unbound.
  explicit Interpreter(const frontend::ast::Program& program, Options options = {});
  ~Interpreter();
  Interpreter(const Interpreter&) = delete;
  Interpreter& operator=(const Interpreter&) = delete;

  // Runs `func` with one value per parameter (in order) and returns its results in order.
  // Generic parameters are bound from the arguments' sizes. Throws RuntimeError.
  std::vector<Value> call(const frontend::ast::FuncDecl& func, std::vector<Value> args);
  // Evaluates an expression that reads no variables (a literal, possibly signed or
  // transposed), e.g. the arguments of a `%!` test. Throws RuntimeError.
  Value evaluate_constant(const frontend::ast::Expr& expr);

  // Binds an extern tensor (the host's job); see interp/set_binding.h for the whole
  // binding interface.
  void set_global(const frontend::ast::Variable& var, Value value);
  // Binds a set to an extern set declaration (checks fields and endpoint sets).
  void bind_set(const frontend::ast::Variable& var, runtime::Set& set);
  runtime::PatternRegistry& patterns() override { return patterns_; }
  const Value& global(const frontend::ast::Variable& var) const override;
  // The value of a parameter, result or local of the innermost active call (for hooks);
  // null when `var` has no value there.
  const Value* local(const frontend::ast::Variable& var) const;

  const Options& options() const { return options_; }
  // The trap point's switch (the host's, or the interpreter's own): a compiled executor
  // looks at it between chunks of elements for a pending interrupt.
  Trap& trap() const override { return *trap_; }
  // Installs (or with null removes) the executor seam's hook between runs: switching the
  // executor copies nothing, the sets and values stay where they are.
  void set_site_hook(SiteHook* sites) { options_.sites = sites; }
  // The storage of a variable of the running function (or a global), for a SiteHook that
  // runs a statement: reads and writes go straight to the interpreter's own values.
  Value& variable(const frontend::ast::Variable& var) override;
  // Runs a statement of the running function without offering it to the SiteHook (what it
  // holds is offered as usual): for a hook whose compiled run of statements hands them back.
  void exec_interpreted(const frontend::ast::Stmt& s) override;

  // ---- Inspection of a paused run, for hooks (the step debugger). Level 0 is the innermost
  // active call (gdb's numbering); frame_count() is 0 when nothing runs. See interp/inspect.h.
  const frontend::ast::Program& program() const override { return program_; }
  int frame_count() const { return depth_; }
  FrameView frame_view(int level) const;
  // The value of `var` in frame `level`: a parameter, result or local of that frame's
  // function, or a global. Null when it has no value (yet).
  const Value* frame_value(int level, const frontend::ast::Variable& var) const;
  // Evaluates a checked debugger expression (frontend/debug_expr.h) in frame `level`
  // without disturbing the paused run: it runs no statement and writes nothing, and the
  // check-finite option is off (a NaN is a value to look at). Calls of user functions and
  // maps are refused. Throws RuntimeError.
  Value evaluate(const frontend::ast::Expr& expr, int level) const override;

  // Wall time spent in outermost `map`/`apply` assemblies (entry to exit, so including the
  // mapped functions and the pattern lookups; nested maps count once, in their outer one).
  // Two clock reads per outermost map and nothing per statement, so always on.
  struct Stats {
    double assembly_seconds = 0.0;
    long maps = 0;  // outermost maps and applies run
  };
  const Stats& stats() const { return stats_; }
  void reset_stats() { stats_ = Stats{}; }

 private:
  struct Frame;
  struct InoutArg;
  struct MapContext;

  // interpreter.cpp: frames, variables, types at run time
  Frame& frame() { return *frames_[depth_]; }
  const Frame& frame() const { return *frames_[depth_]; }
  Value& var(const frontend::ast::Variable& v);
  Value& read_var(const frontend::ast::Variable& v, const frontend::ast::Expr& at);
  [[noreturn]] void fail_unset(const frontend::ast::Variable& v,
                               const frontend::ast::Expr& at) const;
  int dim_size(const frontend::IndexSet& d, const frontend::SourceSpan& at);
  Shape shape_of(const frontend::Type& t, const frontend::SourceSpan& at);
  Value zero_of(const frontend::Type& t, const frontend::SourceSpan& at);
  [[noreturn]] void fail(const frontend::SourceSpan& at, std::string message) const;
  [[noreturn]] void unsupported(const frontend::SourceSpan& at, const char* what) const;
  void finish(Value& v, const frontend::ast::Expr& at);
  void check_result(Value& v, const frontend::ast::Expr& at);
  void check_argument(const frontend::ast::Param& p, const Value& v) const;

  // eval_expr.cpp: expressions
  Value eval(const frontend::ast::Expr& e);
  Value eval_node(const frontend::ast::Expr& e);
  const Value& operand(const frontend::ast::Expr& e, Value& scratch);
  Value eval_dense(const frontend::ast::DenseLit& d);
  Value eval_binary(const frontend::ast::Binary& b);
  Value eval_unary(const frontend::ast::Unary& u);
  Value eval_compare(const frontend::ast::Compare& c);
  Value eval_tensor_read(const frontend::ast::TensorRead& r);
  Value eval_slice(const frontend::ast::TensorRead& r, const Value& base);
  size_t index_value(const frontend::ast::Expr& index, int size);
  size_t checked_index(const Value& v, const frontend::ast::Expr& index, int size);

  // calls.cpp: user functions; intrinsic_calls.cpp: intrinsics
  Value eval_call(const frontend::ast::Call& c);
  Value eval_user_call(const frontend::ast::Call& c);
  static bool has_inout(const frontend::ast::FuncDecl& f);
  static bool is_local(const frontend::ast::Variable& v);
  std::vector<Value> eval_multi(const frontend::ast::Expr& e);
  Frame& run_call(const frontend::ast::Call& c);
  // At the end of an entry call: the arrays an executor keeps newer come home
  // (runtime/residency.h), the call's locals and reusable matrices first dropped when it
  // returned.
  void bring_arrays_home(int base_depth, bool release_locals);
  // The frame above the current one, made ready for a call of `f`: slots sized, each
  // variable referring to its own slot (calls and maps then bind the parameters).
  Frame& next_frame(const frontend::ast::FuncDecl& f, const frontend::SourceSpan& call_site,
                    MapContext* map);
  Frame& enter(const frontend::ast::FuncDecl& f, size_t arg_base, size_t inout_base,
               const frontend::ast::Call* c);
  void bind_generics(const frontend::ast::FuncDecl& f, Frame& callee, const frontend::ast::Call* c);
  void deduce(const frontend::Type& param, const Shape& arg, Frame& callee,
              const frontend::SourceSpan& at);
  void execute_body(const frontend::ast::FuncDecl& f);
  void push_inout_arg(const frontend::ast::Expr& arg, int slot);
  void write_back_inout(size_t inout_base, Frame& callee, const frontend::SourceSpan& at);
  Value call_intrinsic(const frontend::ast::Call& c);
  // The intrinsics with several results (svd, eig, polar).
  std::vector<Value> call_decomposition(const frontend::ast::Call& c);
  Value call_project_spd(const frontend::ast::Call& c, const Value& a);
  // How far the two triangles of an argument of eig or project_spd may differ, relative to
  // its largest component (looser in float32, whose rounding is coarser).
  double symmetry_tolerance() const;

  // hoisting.cpp: calls nested in an expression run first (§6.10)
  class HoistScope {
   public:
    HoistScope(Interpreter& in, const frontend::ast::Expr& root) : in_(in) {
      if (!root.hoisted.empty()) [[unlikely]]
        run(root);  // the common case, no nested call, costs one test
    }
    ~HoistScope() {
      if (active_) [[unlikely]]
        finish();
    }
    HoistScope(const HoistScope&) = delete;
    HoistScope& operator=(const HoistScope&) = delete;

   private:
    void run(const frontend::ast::Expr& root);
    void finish();
    Interpreter& in_;
    size_t saved_base_ = 0;
    bool active_ = false;
  };
  bool take_hoisted(const frontend::ast::Call& c, Value& out);
  Value eval_root(const frontend::ast::Expr& e);

  // places.cpp: assignment targets
  Place resolve_place(const frontend::ast::Expr& target, Value* root_override = nullptr);
  Value read_place(const Place& p) const;
  void write_place(const Place& p, Value value, const frontend::SourceSpan& at);
  void write_place_raw(const Place& p, Value value, const frontend::SourceSpan& at);

  // exec_stmt.cpp: statements
  void exec_block(const frontend::ast::Block& b);
  void exec(const frontend::ast::Stmt& s);
  void exec_trapped(const frontend::ast::Stmt& s);               // the trap point's slow path
  void exec_offered(const frontend::ast::Stmt& s);               // the executor seam for statements
  size_t exec_run(const frontend::ast::Block& b, size_t first);  // ... and for runs of them
  void exec_node(const frontend::ast::Stmt& s);
  void exec_var_decl(const frontend::ast::VarDecl& d);
  void exec_assign(const frontend::ast::Assign& a);
  void store(const frontend::ast::Assign& a, size_t i, Value value);
  void exec_if(const frontend::ast::If& s);
  void exec_for_range(const frontend::ast::ForRange& s);
  void exec_for_set(const frontend::ast::ForSet& s);
  void exec_print(const frontend::ast::Print& p);
  bool condition(const frontend::ast::Expr& e);

  // index_notation.cpp: `C(i, j) = A(i, k) * B(k, j);` by definition (§7.2)
  struct IndexVars;
  void exec_index_assign(const frontend::ast::Assign& a);
  IndexVars index_vars(const frontend::ast::Assign& a);
  Shape ivar_ranges(const frontend::ast::TensorRead& r,
                    std::vector<std::pair<const frontend::ast::Variable*, int>>& sizes);
  void set_ivars(const std::vector<const frontend::ast::Variable*>& vars,
                 const std::vector<int>& values);
  Value reduce(const frontend::ast::Assign& a, const IndexVars& vars);

  // sets.cpp: fields, elements, tuples, grids, loops over sets
  SetBinding& binding_of(const runtime::Set& s, const frontend::SourceSpan& at);
  Value eval_field_read(const frontend::ast::FieldRead& r);
  Value eval_tuple_read(const frontend::ast::TupleRead& r);
  Value eval_set_read(const frontend::ast::SetRead& r);
  Value field_vector(const SetBinding& b, int field);
  Place field_place(const frontend::ast::FieldRead& r);
  Place field_element_place(const SetBinding& b, int field, int element,
                            const frontend::SourceSpan& at);
  Value read_field(const Place& p) const;
  void write_field(const Place& p, Value value, const frontend::SourceSpan& at);
  int set_size(const frontend::ast::Variable& v, const frontend::SourceSpan& at);

  // assembly.cpp: map and apply
  std::vector<Value> eval_map(const frontend::ast::Map& m);
  void exec_apply(const frontend::ast::Apply& a);
  void run_assembly(const frontend::ast::Assembly& a, const frontend::ast::Variable* through,
                    MapContext* ctx, const frontend::SourceSpan& at);
  std::string element_note(const MapContext& ctx) const;
  AssemblyPlan& plan_site(const frontend::ast::Assembly& a, const MapContext& ctx);
  std::shared_ptr<runtime::SystemMatrix> result_matrix(AssemblyPlan::Result& r,
                                                       const runtime::PatternPtr& pattern,
                                                       int block_rows, int block_cols,
                                                       ComponentKind kind);
  Place matrix_place(const frontend::ast::TensorRead& r, Value& m);
  int member_of(const frontend::ast::Expr& index);
  int32_t member_block(const frontend::ast::TensorRead& r, const Value& m);
  bool result_write(const frontend::ast::Expr& target, Value& value);
  bool block_component(const frontend::ast::TensorRead& r, Place& p);
  static int local_member(const std::vector<int>& members, int member);
  void check_vector_write(const frontend::ast::TensorRead& r, const Value& element);
  bool is_map_result(const Value* v) const;
  Value finish_grid_result(MapContext& ctx, size_t result);

  // distributed.cpp: a distributed run (interp/distribution.h)
  // The set a global vector of type `t` runs over, in a distributed run (null otherwise).
  const runtime::Set* distributed_set(const frontend::Type* t);
  [[noreturn]] void not_distributed(const frontend::SourceSpan& at, const std::string& what) const;
  // x' y (or with `root`, its square root) over `set`: the owned elements, then every rank's.
  Value distributed_inner_product(const Value& x, const Value& y, const runtime::Set& set,
                                  bool root, const frontend::SourceSpan& at);
  // A \ b over the ranks (Distribution::solve), its ghosts refreshed.
  Value distributed_solve(const frontend::ast::Binary& b, const runtime::SystemMatrix& a,
                          const Value& rhs);
  // Ghost entries of a global vector of type `t` from their owners (after a partial write).
  void refresh_ghosts(Value& v, const frontend::Type* t);

  // linalg.cpp: system values in operators and intrinsics
  bool system_binary(const frontend::ast::Binary& b, const Value& l, const Value& r, Value& out);
  bool scaled_matrix_sum(const frontend::ast::Binary& b, Value& out);
  Value matrix_read(const frontend::ast::TensorRead& r, const Value& m);
  Value solver_intrinsic(const frontend::ast::Call& c, std::vector<Value>& args);

  runtime::PatternRegistry patterns_;
  // One plan per map / apply site (assembly_plan.h).
  std::unordered_map<const frontend::ast::Assembly*, AssemblyPlan> plans_;
  std::vector<std::unique_ptr<SetBinding>> bindings_;
  MapContext* map_ = nullptr;  // the innermost running map
  int map_depth_ = -1;         // the depth of its mapped function's frame
  // Assembly timing: maps can nest (a mapped function may call a function that maps), so
  // only the transition from no running assembly to one is timed.
  class AssemblyTimer;
  int assembly_depth_ = 0;
  Stats stats_;

  const frontend::ast::Program& program_;
  Options options_;
  // The trap point's switch: the host's (Options::trap) or our own, holding Options::hook.
  Trap own_trap_;
  Trap* trap_ = &own_trap_;
  uint64_t activations_ = 0;   // numbers every call and mapped element (FrameView::activation)
  bool post_process_ = false;  // float32 or check_finite: results need a second look
  std::vector<Value> globals_;
  std::vector<std::unique_ptr<Frame>> frames_;  // reused by depth; index 0 is a base frame
  int depth_ = 0;
  // Arguments being evaluated for pending calls: a value, or the caller's variable itself.
  struct Arg {
    Value value;
    Value* ref = nullptr;
  };
  std::vector<Arg> arg_stack_;
  std::vector<InoutArg> inout_stack_;  // inout arguments of pending calls
  std::vector<std::pair<const frontend::ast::Call*, Value>> hoisted_;  // results waiting
  size_t hoist_base_ = 0;  // the innermost root's results start here
};

}  // namespace simit::interp
