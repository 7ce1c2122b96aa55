// The program's fused matrix sums (jit/matrix_sum.h) run on their compiled operands.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <functional>
#include <sstream>

#include "interp/exec_state.h"
#include "interp/runtime_error.h"
#include "interp/set_binding.h"
#include "jit/controller_state.h"
#include "jit/matrix_sum.h"
#include "jit/pruned_matrix.h"
#include "jit/specialise.h"
#include "jit/write_guard.h"
#include "runtime/lazy_sum.h"
#include "runtime/system_ops.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;

const FusedSums& TraceController::fused_sums(const interp::ExecState& in) {
  if (!fused_) fused_ = find_fused_sums(in.program());
  return *fused_;
}

// `A = M - s * K` in K's storage (jit/matrix_sum.h). Under float32 s * K and the sum are each
// rounded to binary32, as the interpreter rounds them. Declined under check-finite, where the
// interpreter looks at s * K on its own, and when M has a block outside K's pattern.
bool TraceController::run_fused_sum(const ast::Stmt& stmt, const FusedSum& sum,
                                    interp::ExecState& in) {
  if (!target_ || options_.check_finite || checking_run_) return false;
  SumState& s = sums_[&stmt];
  if (s.stats.site.empty()) {
    s.stats.line = static_cast<int>(stmt.span.start().line);
    s.stats.site = "statement (line " + std::to_string(s.stats.line) + ")";
    s.stats.key = sum.target->name + " = " + sum.base->name + (sum.subtract ? " - " : " + ") +
                  "s * " + sum.scaled->name + " in the storage of " + sum.scaled->name +
                  " (the map on line " + std::to_string(sum.producer_line) + ")";
  }
  // A production run fuses from the first call: the interpreter's sum would make A on the
  // full pattern beside K (31 MB on dragon160k).
  if (++s.runs <= options_.threshold && !options_.eager) return false;
  const Value& kv = in.variable(*sum.scaled);
  const Value& mv = in.variable(*sum.base);
  if (kv.kind() != Value::Kind::Matrix || mv.kind() != Value::Kind::Matrix || !kv.matrix() ||
      !mv.matrix())
    return false;
  const Value factor = in.evaluate(*sum.factor, 0);
  if (factor.kind() != Value::Kind::Float) return false;
  const double beta = sum.subtract ? -factor.as_float() : factor.as_float();
  const std::shared_ptr<runtime::SystemMatrix> k = kv.matrix();
  const std::shared_ptr<runtime::SystemMatrix> m = mv.matrix();
  std::optional<runtime::SystemMatrix> want;
  if (options_.check && options_.float32) {
    // The interpreter's float32 order: s * K rounded, then M -/+ it rounded.
    runtime::SystemMatrix scaled = runtime::scaled(factor.as_float(), *k);
    runtime::round_to_float32(scaled);
    want = runtime::add(*m, scaled, 1.0, sum.subtract ? -1.0 : 1.0, &in.patterns());
    runtime::round_to_float32(*want);
  } else if (options_.check) {
    want = runtime::add(*m, *k, 1.0, beta, &in.patterns());
  }
  CallTimer timer(s.stats);
  // On the GPU where its map left K (the device's copy newest), else on the host.
  const bool on_device =
      device_executor_ && device_executor_->add_into(*m, 1.0, *k, beta, options_.float32);
  // --float32 on the CPU: a solver loop copies A into binary32 before it reads it, and sums
  // it there block by block (jit/pending_sums.h), saving a pass over K that writes every
  // value (on fem dragon160k 13.7 MB, 1.9% of a frame).
  const bool pending = !on_device && !device_executor_ && options_.float32 && !want &&
                       k->block_size() <= runtime::LazySum::kMaxBlock && s.fits(*m, *k);
  if (on_device) {
    s.stats.note = options_.gpu_emulated ? "; on the GPU (emulated)" : "; on the GPU";
  } else if (pending) {
    double* host = k->values();  // home first (as add_into would read them)
    pending_sums_.hold(
        host, runtime::LazySum(m, 1.0, k->shared_pattern(), host, k->block_size(), beta, true));
    ++s.pending;
  } else if (!runtime::add_into(
                 *m, 1.0, *k, beta,
                 [this](int64_t tasks, const std::function<void(int64_t)>& task) {
                   executor_->for_each(tasks, task);
                 },
                 options_.float32)) {
    s.stats.status =
        "interpreted: " + sum.base->name + " has blocks outside the pattern of " + sum.scaled->name;
    return false;
  }
  timer.done();
  s.stats.status = "fused";
  if (want) {
    const runtime::MatrixPattern &pw = want->pattern(), &pk = k->pattern();
    if (pw.row_ptr() != pk.row_ptr() || pw.col_idx() != pk.col_idx())
      throw interp::RuntimeError(stmt.span,
                                 "--check-jit: the fused sum's pattern differs from "
                                 "the interpreter's for '" +
                                     sum.target->name + "'");
    for (size_t c = 0; c < want->value_count(); ++c)
      if (!same_bits(want->values()[c], k->values()[c]))
        throw interp::RuntimeError(
            stmt.span, "--check-jit: the fused sum differs from the interpreter in '" +
                           sum.target->name + "' component " + std::to_string(c) + " (block " +
                           std::to_string(c / static_cast<size_t>(k->block_size())) +
                           "): interpreted " + number(want->values()[c]) + ", compiled " +
                           number(k->values()[c]));
  }
  // K is dead, but a debugger stopped later (Ctrl-C) could still print it: it has no value
  // rather than the sum's.
  in.variable(*sum.scaled) = Value();
  in.variable(*sum.target) = Value::of_matrix(k);
  return true;
}

}  // namespace simit::jit
