// The tracer: turns one planned map or apply site into a loop-IR trace by running its mapped
// function symbolically, once, for a generic element.
//
// Calls are inlined, loops over constant ranges unrolled and small dense tensors split into
// their components while tracing; conditions that fold to constants choose their branch, and
// the others become If statements. Whatever the tracer does not handle (a loop whose bounds
// are not constants, a read of the function's own result, a stencil map, a print) makes it
// give up with the reason, and the site stays interpreted.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "frontend/ast.h"
#include "interp/value.h"
#include "jit/loop_ir.h"
#include "runtime/set.h"
#include "runtime/system_matrix.h"

namespace simit::jit {

// Where a scalar argument of the trace comes from at each call: a component of a partial
// argument of the site (`map f(mu, lambda) to S`), or of an extern tensor of the program.
struct ScalarSource {
  int partial = -1;                                 // partial argument, or -1
  const frontend::ast::Variable* global = nullptr;  // an extern, when partial < 0
  int component = 0;
};

// What the tracer needs to know about one execution of a site.
struct SiteShape {
  const frontend::ast::Assembly* site = nullptr;
  const runtime::Set* target = nullptr;
  bool reduce = false;
  bool float32 = false;
  bool check_finite = false;  // a check after every operation, as the interpreter's
  // Per result: its pattern when it is a system matrix (null for vectors).
  std::vector<const runtime::MatrixPattern*> patterns;
  const std::vector<interp::Value>* partial_args = nullptr;
  // The value of a global (constants are folded in; externs become scalar arguments).
  std::function<const interp::Value*(const frontend::ast::Variable&)> global;
};

struct TracedSite {
  std::optional<Trace> trace;
  std::string reason;                        // why there is no trace
  std::vector<ScalarSource> scalar_sources;  // one per Trace::scalars entry
};

TracedSite trace_site(const SiteShape& shape);

}  // namespace simit::jit
