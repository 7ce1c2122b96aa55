// The loop IR a traced map site is compiled from: scalar expressions and statements run once
// per element of the target set, with every array the kernel touches named by a slot.
//
// A trace is scalar code: the tracer (jit/trace_site.h) has already inlined the calls,
// unrolled the loops over constant ranges and split every small dense tensor into its
// components, so what is left is arithmetic, loads, guarded blocks and the assembly writes.
// The exception is tensors of more than 144 components (a product too large to unroll, a
// large field, an outer product, and element-wise operations and matrix-vector products on
// them: tiled dense tensors): their operands and results lie in per-element scratch arrays,
// and they run as loops (a product over 12 x 12 tiles).
// Every node keeps the source span it came from, so a failing check names the `.sim` line.
#pragma once

#include <cstdint>
#include <memory>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "frontend/source.h"

namespace simit::jit {

// Scalar types of the IR: binary64, 32-bit int, and truth values.
enum class Ty : uint8_t { F64, I32, Bool };
const char* ty_name(Ty t);

// One list of expression kinds and one of statement kinds; the enums, the printer's names
// and the verifier's dispatch derive from them.
#define SIMIT_LOOP_EXPRS(X)                                                        \
  X(Const)    /* f (F64) or i (I32, Bool)                                       */ \
  X(Scalar)   /* the call's scalar argument `slot`                              */ \
  X(Element)  /* the index of the visited element                               */ \
  X(Endpoint) /* endpoint `slot` of the visited element                         */ \
  X(Load)     /* component `comp` (+ ops[1]) of array `slot` at ops[0]         */  \
  X(Local)    /* the value of local `slot`                                      */ \
  X(Unary)    /* op(ops[0])                                                     */ \
  X(Binary)   /* ops[0] op ops[1]                                               */ \
  X(Compare)  /* ops[0] op ops[1], a Bool                                       */ \
  X(Select)   /* ops[0] ? ops[1] : ops[2]                                       */ \
  X(Math)     /* C library function `op` of ops                                 */ \
  X(Scratch)  /* component ops[0] (an I32) of the element's scratch array `slot`  */
#define SIMIT_LOOP_STMTS(X)                                                           \
  X(SetLocal)  /* local `slot` = value                                            */  \
  X(Store)     /* array `slot` at element `index`, component `comp` = value       */  \
  X(Assemble)  /* result `slot` += (or =) value, at a vector element or a block    */ \
  X(If)        /* if value then body else orelse                                  */  \
  X(Check)     /* if not value: stop with error `error`                           */  \
  X(Decompose) /* outs = decomposition `fn` of the n x n matrix args, or error   */   \
  X(Put)       /* scratch array `slot` at component `index` = value (an F64)      */  \
  X(For)       /* for I32 local `slot` = 0 .. n - 1: body                          */

enum class ExprKind : uint8_t {
#define SIMIT_LOOP_ENUM(n) n,
  SIMIT_LOOP_EXPRS(SIMIT_LOOP_ENUM)
};
enum class StmtKind : uint8_t { SIMIT_LOOP_STMTS(SIMIT_LOOP_ENUM) };
#undef SIMIT_LOOP_ENUM
const char* expr_kind_name(ExprKind k);
const char* stmt_kind_name(StmtKind k);

enum class UnOp : uint8_t { Neg, Not, Round32, ToF64 };
// Div on I32 truncates, Mod is the remainder of that division (the sign of the dividend); a
// target computes both without trapping (a zero divisor's check fails before its value is
// used, and `x / -1` wraps as the interpreter's does).
enum class BinOp : uint8_t { Add, Sub, Mul, Div, And, Or, Xor, Mod };
enum class CmpOp : uint8_t { Eq, Ne, Lt, Gt, Le, Ge };
enum class MathFn : uint8_t {
  Sin,
  Cos,
  Tan,
  Asin,
  Acos,
  Atan2,
  Sqrt,
  Cbrt,
  Log,
  Exp,
  Pow,
  Abs,
  Max,
  Min
};
const char* math_name(MathFn f);
// The decompositions a trace calls into the runtime for (docs/intrinsics.md).
enum class Decomposition : uint8_t { Svd, Eig, Polar, ProjectSpd, ProjectSpdAbs };
// Components each of its results has, for an n x n argument.
std::vector<int> decomposition_results(Decomposition d, int n);

struct Expr;
using ExprRef = std::shared_ptr<const Expr>;

struct Expr {
  ExprKind kind = ExprKind::Const;
  Ty ty = Ty::F64;
  uint8_t op = 0;  // UnOp, BinOp, CmpOp or MathFn by kind
  int slot = 0;    // Scalar, Endpoint, Load, Local, Scratch
  int comp = 0;    // Load
  double f = 0.0;  // Const F64
  int64_t i = 0;   // Const I32 / Bool
  std::vector<ExprRef> ops;
  frontend::SourceSpan span;
  // F64: the value may be a zero of the other sign than the interpreter's (jit/zero_fold.h).
  bool loose = false;
};

struct Stmt {
  StmtKind kind = StmtKind::SetLocal;
  // SetLocal, For: local; Store: array; Assemble: result array; Put: scratch array
  int slot = 0;
  int comp = 0;   // Store / Assemble: component within the element's block
  int pair = -1;  // Assemble into a matrix: the (row member, column member) pair
  // Assemble into a vector of a deferred trace (jit/defer_assembly.h): the member written
  // (0: the element, k + 1: endpoint k), whose block the result's Table gives.
  int member = -1;
  int error = -1;  // Check: index into Trace::errors
  // Store / Assemble into a vector: the element written; Put: the component written.
  ExprRef index;
  // SetLocal, Store, Assemble, Put: the value; If, Check: the condition.
  ExprRef value;
  std::vector<Stmt> body, orelse;  // If; For (body only)
  // For: the trip count n. Decompose: a decomposition of the runtime (Decomposition) of the
  // n x n matrix `args`, row-major, into the locals `outs` (its results one after another,
  // each row-major).
  int fn = 0, n = 0;
  std::vector<ExprRef> args;
  std::vector<int> outs;
  frontend::SourceSpan span;
};

// What an array slot of a trace holds; the controller fills the pointers per call.
struct ArraySlot {
  enum class Kind : uint8_t {
    Field,   // a field of `member` (0: the target set, k + 1: endpoint set k)
    Vector,  // a partial argument that is a global vector (one block per element)
    Result,  // result `index`'s components (a global vector or a matrix's values)
    Table,   // result `index`'s per-element block table (AssemblyIndex::table)
    Marks,   // result `index`'s marks, a byte per block, or null (see jit/write_guard.h)
    Matrix,  // a partial argument that is a global matrix: its values, one block per position
    // Per element, where in partial matrix argument `index`'s pattern each block the trace
    // reads lies (-1: outside it), one component per entry of `reads`.
    Positions,
    // Result `index`'s deferred blocks (jit/defer_assembly.h): a Table entry -1 - k sends the
    // write to block k here instead of the result.
    Deferred,
  };
  Kind kind = Kind::Field;
  int member = 0;       // Field
  int index = 0;        // Field: the set's field index; Vector: partial argument; Result, Table
  Ty ty = Ty::F64;      // component type as stored
  bool single = false;  // binary32 storage of a float field
  bool written = false;
  int components = 1;  // per element (per block for results)
  std::string name;    // for dumps and messages
  // Positions: the (row member, column member) of each block read, by component.
  std::vector<std::pair<int, int>> reads;
};

// A run-time check that failed: where, and what to say.
struct ErrorSite {
  frontend::SourceSpan span;
  std::string message;
  // The inlined calls it lies in, innermost first: each callee and the span of its call, for
  // the call stack the interpreter would report.
  std::vector<std::pair<std::string, frontend::SourceSpan>> frames = {};
};

// One compiled unit: the per-element body of a map or apply site.
struct Trace {
  std::string name;     // e.g. "tet_force@fem.sim:165"
  int arity = 0;        // endpoints per element of the target set
  bool reduce = false;  // assembly writes add (else they overwrite)
  std::vector<ArraySlot> arrays;
  std::vector<Ty> scalars;  // the call's scalar arguments, by slot
  std::vector<Ty> locals;   // local slots, by number
  // Per local: whether it is set more than once (a variable assigned in a branch). The others
  // are set exactly once, before every read, and become SSA values.
  std::vector<bool> local_mutable;
  std::vector<int> pairs;  // per matrix result (by result index): pairs per element, or 0
  std::vector<Stmt> body;
  std::vector<ErrorSite> errors;
  // Components of each per-element scratch array (binary64), by slot: the operands and
  // results of tiled products, rewritten for every element.
  std::vector<int> scratch;
  bool writes_fields = false;  // some Store (an apply with inout fields)
  bool float32 = false;        // the interpreter's float32 mode (decompositions' tolerance)
  // Assembly writes go through per-element tables, to the result or to its Deferred blocks
  // (jit/defer_assembly.h), so that chunks of elements can run apart.
  bool deferred = false;
};

// A run of system-level statements (a CG function's set-up, its while loop and its residual):
// scalar statements, fused passes over the components of global vectors, and sparse
// matrix-vector products, before, inside and after at most one while loop.
// Vectors are arrays of one-component elements indexed by the component (ExprKind::Element
// is the component in a pass); locals 0 .. scalars-1 are the program's scalar variables,
// read from the scalar array on entry and written back on exit.
struct VectorOp {
  enum class Kind : uint8_t {
    Scalar,  // body once
    Pass,    // body for each component k < sizes[length] (a fused loop)
    SpMV,    // arrays[y] = matrix * arrays[x], row block by row block; then body for each
             // component of the row just computed (a fused reduction over y)
  };
  Kind kind = Kind::Scalar;
  std::vector<Stmt> body;
  int length = -1;                           // Pass: index into the sizes
  int row_ptr = -1, cols = -1, values = -1;  // SpMV: the matrix's arrays
  int rows = -1;                             // SpMV: index into the sizes (block rows)
  int x = -1, y = -1;                        // SpMV: vector arrays
  int block = 1;                             // SpMV: block rows = block columns
  // Inner products (docs/arithmetic.md) sum each element's block first: the locals in `sums`
  // are reductions `s = s + term` whose terms arrive in runs of `group` components (one
  // element; an SpMV's row); each run is summed on its own, then added to s.
  int group = 1;
  std::vector<int> sums;
  // A Bool local: the op runs only when it holds (the op is in a branch of an `if`), or -1.
  int guard = -1;
};

struct SystemTrace {
  std::string name;
  std::vector<ArraySlot> arrays;
  std::vector<Ty> locals;
  int scalars = 0;                 // the first locals: the program's scalars, in and out
  std::vector<std::string> sizes;  // what each size is (for dumps)
  std::vector<VectorOp> before;    // ops run once, before the loop
  ExprRef condition;               // the while condition; null when the run has no loop
  std::vector<VectorOp> body;      // the loop's ops, per iteration
  std::vector<VectorOp> after;     // ops run once, after the loop
  // The loop's error statements (Check statements in its scalar ops): a kernel that reaches
  // one returns 1 + its index, and the controller hands the loop back to the interpreter.
  std::vector<ErrorSite> errors;
  // A run without a loop multiplies once by each matrix: its products read the matrices' own
  // arrays (blocks row-major, zero blocks included, as the interpreter's product reads them)
  // rather than a copy without zero blocks, whose blocks are column-major (PrunedMatrix).
  bool matrices_in_place = false;
  // Compiled as a device program (jit/device_program.h): its steps as kernels of their own,
  // the scalars in device memory, for an executor whose memory is elsewhere (the GPU's).
  bool device = false;
  // --float32: a product's row sums add in binary32 steps (docs/arithmetic.md), each product
  // and addition rounded, as runtime::multiply sums them.
  bool float32 = false;
};

// Prints the trace as text (`--dump=loop-ir`).
void print(std::ostream& os, const Trace& t);
void print(std::ostream& os, const SystemTrace& t);
// Merges adjacent passes over the same vectors into one loop, folds a reduction over a
// product's result into the product's row loop, and moves scalar statements that do not
// depend on a pass above it (jit/fuse_passes.cpp). Returns the number of loops removed.
int fuse_passes(SystemTrace& t);
// The same for one list of ops (one section of a trace).
int fuse_passes(std::vector<VectorOp>& ops);
// Checks the invariants every pass relies on: operand types, slots in range, locals set
// before they are read on every path. Returns the first violation, or "" when it holds.
std::string verify(const Trace& t);
// The same for a system trace, whose first `scalars` locals are set on entry.
std::string verify(const SystemTrace& t);
// Counts the nodes of a trace (for size limits and statistics).
size_t node_count(const Trace& t);
size_t node_count(const SystemTrace& t);  // its ops (one each) and their statements

}  // namespace simit::jit
