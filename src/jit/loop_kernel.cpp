// A system kernel's call (a while loop, a run of statements): the interpreter's variables
// marshalled in and out, an error statement handed back, an interrupt between iterations.
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
#include "runtime/system_ops.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;

namespace {

// The scalars a kernel stopped by an interrupt hands back: those the ops before the loop and
// its iterations write (the ops after it did not run; a scalar only they write keeps its value).
std::vector<bool> scalars_written_up_to_loop(const SystemTrace& t) {
  std::vector<bool> out(static_cast<size_t>(t.scalars), false);
  for (const auto* ops : {&t.before, &t.body})
    for (const VectorOp& op : *ops) note_scalar_writes(op.body, t.scalars, out);
  return out;
}

// Where the interpreter takes an interrupt that arrives between two iterations: before the
// first statement of the next one (the loop itself when its body is empty).
const ast::Stmt& interrupted_at(const std::vector<const ast::Stmt*>& run) {
  for (const ast::Stmt* s : run)
    if (const auto* loop = s->as<ast::While>())
      return loop->body.empty() ? *s : *loop->body.front();
  return *run.front();
}

}  // namespace

// The lengths a system trace's sizes name, as the interpreter's values hold them now (-1
// where a value is missing or of another kind).
std::vector<int64_t> current_sizes(const SystemBinding& b, interp::ExecState& in) {
  std::vector<int64_t> out;
  for (const SystemBinding::Size& s : b.sizes) {
    const Value& v = in.variable(*s.var);
    if (s.field >= 0) {
      const bool bound = v.kind() == Value::Kind::Set && v.binding() && v.binding()->set;
      out.push_back(bound ? static_cast<int64_t>(v.binding()->set->size()) *
                                std::as_const(*v.binding()->set)
                                    .field(v.binding()->fields[s.field])
                                    .components()
                          : -1);
    } else if (s.rows)
      out.push_back(v.kind() == Value::Kind::Matrix && v.matrix() ? v.matrix()->rows() : -1);
    else
      out.push_back(v.is_tensor() ? static_cast<int64_t>(v.tensor().size()) : -1);
  }
  // A kernel reads each field in the storage it was traced for (binary32 or binary64).
  for (const SystemBinding::Array& a : b.arrays) {
    if (a.part != SystemBinding::Array::Part::Field) continue;
    const Value& v = in.variable(*a.var);
    const bool bound = v.kind() == Value::Kind::Set && v.binding() && v.binding()->set;
    out.push_back(
        bound ? std::as_const(*v.binding()->set).field(v.binding()->fields[a.field]).type().single
              : -1);
  }
  return out;
}

// Marks the program scalars (locals below `scalars`) a block sets, in branches too.
void note_scalar_writes(const std::vector<Stmt>& body, int scalars, std::vector<bool>& writes) {
  for (const Stmt& st : body) {
    if (st.kind == StmtKind::SetLocal && st.slot < scalars) writes[st.slot] = true;
    note_scalar_writes(st.body, scalars, writes);
    note_scalar_writes(st.orelse, scalars, writes);
  }
}

// The field a Field array of a system trace names (its set is bound: the sizes matched).
runtime::Field& bound_field(const SystemBinding::Array& a, interp::ExecState& in) {
  const interp::SetBinding& b = *in.variable(*a.var).binding();
  return b.set->field(b.fields[a.field]);
}

// The first n components of a float field as binary64 (binary32 storage widens exactly),
// and back (binary32 storage takes values that came from it, exactly).
std::vector<double> field_values(const runtime::Field& f, size_t n) {
  if (!f.type().single) return std::vector<double>(f.data<double>(), f.data<double>() + n);
  const float* v = f.data<float>();
  return std::vector<double>(v, v + n);
}

void set_field_values(runtime::Field& f, const std::vector<double>& values) {
  if (!f.type().single) {
    std::copy(values.begin(), values.end(), f.data<double>());
    return;
  }
  float* v = f.data<float>();
  for (size_t k = 0; k < values.size(); ++k) v[k] = static_cast<float>(values[k]);
}

// The variables a loop writes, as shared copies: a vector the kernel writes is copied by
// its first write (copy on write), so keeping the old value costs one copy of each written
// vector per call, and only for loops that may stop.
Saved save_loop_variables(const SystemBinding& b, const SystemTrace& t,
                          const std::vector<bool>& writes_scalar, interp::ExecState& in) {
  Saved out;
  for (size_t i = 0; i < b.arrays.size(); ++i)
    if (t.arrays[i].written && b.arrays[i].var &&
        b.arrays[i].part != SystemBinding::Array::Part::Field)
      out.emplace_back(b.arrays[i].var, in.variable(*b.arrays[i].var));
  for (size_t i = 0; i < b.scalars.size(); ++i)
    if (writes_scalar[i]) out.emplace_back(b.scalars[i], in.variable(*b.scalars[i]));
  return out;
}

// Runs the loop's kernel on the interpreter's variables. A loop that reaches an error
// statement is put back as it was and left to the interpreter (false), which runs it from
// the start and stops with the error in its own words, at its line. A loop that an interrupt
// (Ctrl-C) stops between two iterations keeps what they wrote and throws interp::Interrupted.
bool TraceController::run_loop_kernel(LoopEntry& entry, interp::ExecState& in) {
  LoopEntry* e = &entry;
  CallTimer timer(e->stats);
  const SystemBinding& b = e->traced.binding;
  const SystemTrace& t = *e->traced.trace;
  // A matrix or vector with a value that is not a binary32 value, where the kernel holds a
  // binary32 copy (--float32): the call is left to the interpreter.
  auto leave_wide = [e](const ast::Variable& var) {
    ++e->not_binary32;
    e->stats.note = "; " + std::to_string(e->not_binary32) + " call" +
                    (e->not_binary32 > 1 ? "s" : "") + " ran interpreted: '" + var.name +
                    "' holds values that are not binary32";
    return false;
  };
  // The matrices are constant while the loop runs: their zero blocks are dropped once, before
  // anything is bound. Under --float32 the copy is binary32; a matrix with a value that is
  // not one (bound by the host) leaves the call to the interpreter.
  if (!t.matrices_in_place)
    for (size_t i = 0; i < b.arrays.size(); ++i) {
      if (b.arrays[i].part != SystemBinding::Array::Part::Values) continue;
      const double before = thread_cpu_ms();
      PrunedMatrix& p = e->pruned[b.arrays[i].var];
      const runtime::SystemMatrix& m = *in.variable(*b.arrays[i].var).matrix();
      // A fused sum left pending in m's values is summed as the copy reads it.
      const bool exact = p.assign(
          m, t.arrays[i].single,
          [this](int64_t tasks, const std::function<void(int64_t)>& task) {
            executor_->for_each(tasks, task);
          },
          rows_in_pairs(t, t.arrays[i], m.block_rows()), pending_sums_.find(m.raw_values()));
      e->prune_cpu_ms += thread_cpu_ms() - before;
      if (!exact) return leave_wide(*b.arrays[i].var);
      e->kept += p.kept;
      e->total += p.total;
    }
  // Under float32 the loop's vectors are binary32 copies: each value must be a binary32 value.
  for (size_t i = 0; i < b.arrays.size(); ++i) {
    if (!t.arrays[i].single || b.arrays[i].part != SystemBinding::Array::Part::Vector) continue;
    const Value& v = in.variable(*b.arrays[i].var);
    if (v.empty() || !v.is_tensor() || v.tensor().kind() != runtime::ComponentKind::Float)
      continue;  // created below
    if (!runtime::is_binary32(std::span(v.tensor().floats(), v.tensor().size())))
      return leave_wide(*b.arrays[i].var);
  }
  Saved saved;
  if (!t.errors.empty()) saved = save_loop_variables(b, t, e->writes_scalar, in);
  // A vector first assigned in the loop or run is made with the shape of its model: a value
  // left from an earlier run through the same statements may have another.
  for (const SystemBinding::Created& c : b.created) {
    runtime::Shape shape;
    if (c.like_field >= 0) {
      const interp::SetBinding& sb = *in.variable(*c.like).binding();
      shape =
          runtime::Shape::blocked(std::vector<int>{sb.set->size()}, sb.field_shapes[c.like_field]);
    } else {
      shape = in.variable(*c.like).tensor().shape();
    }
    const Value& now = in.variable(*c.var);
    if (now.empty() || !now.is_tensor() || now.tensor().size() != shape.size() ||
        now.tensor().kind() != runtime::ComponentKind::Float)
      in.variable(*c.var) = Value::of_tensor(runtime::Tensor(runtime::ComponentKind::Float, shape));
  }
  std::vector<void*> arrays(b.arrays.size(), nullptr);
  std::vector<size_t> bytes(b.arrays.size(), 0);  // for an executor that copies them
  // Runtime arrays the device may keep what it wrote in until the host touches them
  // (runtime/residency.h): taken on the device's side without bringing them back.
  const bool resident = e->on_device;
  std::vector<uint8_t> runtime_array(b.arrays.size(), 0);
  for (int pass = 0; pass < 2; ++pass)
    for (size_t i = 0; i < b.arrays.size(); ++i) {
      if (t.arrays[i].written != (pass == 0)) continue;
      using Part = SystemBinding::Array::Part;
      if (b.arrays[i].part == Part::Scratch) {
        const size_t n = static_cast<size_t>(e->sizes[static_cast<size_t>(b.arrays[i].size)]);
        if (t.arrays[i].single) {
          e->single.resize(b.arrays.size());
          e->single[i].resize(n);
          arrays[i] = e->single[i].data();
          bytes[i] = n * sizeof(float);
          continue;
        }
        e->scratch.resize(b.arrays.size());
        e->scratch[i].resize(n);
        arrays[i] = e->scratch[i].data();
        bytes[i] = n * sizeof(double);
        continue;
      }
      Value& v = in.variable(*b.arrays[i].var);
      switch (b.arrays[i].part) {
        case Part::Vector:
          if (t.arrays[i].single) {  // copied in (exactly: checked above)
            const runtime::Tensor& x = v.tensor();
            e->single.resize(b.arrays.size());
            std::vector<float>& s = e->single[i];
            const double* from = x.floats();
            s.resize(x.size());
            for (size_t k = 0; k < s.size(); ++k) s[k] = static_cast<float>(from[k]);
            arrays[i] = s.data();
            bytes[i] = s.size() * sizeof(float);
            break;
          }
          if (resident)
            arrays[i] = t.arrays[i].written ? static_cast<void*>(v.tensor().raw_mutable_floats())
                                            : const_cast<double*>(v.tensor().raw_floats());
          else
            arrays[i] = t.arrays[i].written ? static_cast<void*>(v.tensor().mutable_floats())
                                            : const_cast<double*>(v.tensor().floats());
          bytes[i] = v.tensor().size() * sizeof(double);
          runtime_array[i] = v.tensor().shared_buffer() ? 1 : 0;
          break;
        case Part::RowPtr: {
          const std::vector<int32_t>& r = t.matrices_in_place ? v.matrix()->pattern().row_ptr()
                                                              : e->pruned[b.arrays[i].var].row_ptr;
          arrays[i] = const_cast<int32_t*>(r.data());
          bytes[i] = r.size() * sizeof(int32_t);
          break;
        }
        case Part::Cols: {
          const std::vector<int32_t>& c = t.matrices_in_place ? v.matrix()->pattern().col_idx()
                                                              : e->pruned[b.arrays[i].var].cols;
          arrays[i] = const_cast<int32_t*>(c.data());
          bytes[i] = c.size() * sizeof(int32_t);
          break;
        }
        case Part::Values:
          if (t.matrices_in_place) {
            arrays[i] = const_cast<double*>(resident ? std::as_const(*v.matrix()).raw_values()
                                                     : std::as_const(*v.matrix()).values());
            bytes[i] = v.matrix()->value_count() * sizeof(double);
            runtime_array[i] = 1;
          } else if (t.arrays[i].single) {
            arrays[i] = e->pruned[b.arrays[i].var].values32.data();
            bytes[i] = e->pruned[b.arrays[i].var].values32.size() * sizeof(float);
          } else {
            arrays[i] = e->pruned[b.arrays[i].var].values.data();
            bytes[i] = e->pruned[b.arrays[i].var].values.size() * sizeof(double);
          }
          break;
        case Part::Field: {
          runtime::Field& f = bound_field(b.arrays[i], in);
          // A write counts in the field's write version (and unshares its array).
          if (resident)
            arrays[i] = t.arrays[i].written ? static_cast<void*>(f.raw_bytes())
                                            : const_cast<std::byte*>(std::as_const(f).raw_bytes());
          else if (f.type().single)
            arrays[i] = t.arrays[i].written ? static_cast<void*>(f.data<float>())
                                            : const_cast<float*>(std::as_const(f).data<float>());
          else
            arrays[i] = t.arrays[i].written ? static_cast<void*>(f.data<double>())
                                            : const_cast<double*>(std::as_const(f).data<double>());
          runtime_array[i] = 1;
          bytes[i] = in.variable(*b.arrays[i].var).binding()->set->size() * f.element_bytes();
          break;
        }
        case Part::Scratch: break;
      }
    }
  std::vector<double> scalars(b.scalars.size(), 0.0);
  for (size_t i = 0; i < b.scalars.size(); ++i) {
    const Value& v = in.variable(*b.scalars[i]);
    if (!v.empty()) scalars[i] = component(v, 0);
  }
  interp::Trap& trap = in.trap();
  SystemArgs args{arrays.data(), scalars.data(), e->sizes.data(), trap.interrupt_flag()};
  std::unique_ptr<bool[]> array_written(new bool[b.arrays.size() + 1]);
  for (size_t i = 0; i < b.arrays.size(); ++i) array_written[i] = t.arrays[i].written;
  args.array_count = b.arrays.size();
  args.size_count = t.sizes.size();
  args.scalar_count = b.scalars.size();
  args.array_bytes = bytes.data();
  args.array_written = array_written.get();
  args.array_resident = runtime_array.data();
  int64_t iterations = 0;
  args.iterations = &iterations;
  const auto kernel_start = std::chrono::steady_clock::now();
  const int32_t rc = (e->on_device ? *device_executor_ : *executor_).run_system(*e->kernel, args);
  if (!e->traffic_plan) e->traffic_plan = plan_traffic(t);
  e->traffic.add(
      e->traffic_plan->bytes(bytes), iterations,
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - kernel_start)
          .count());
  // Ctrl-C: the loop stopped between two iterations. What it wrote stays (fields are written
  // in place and cannot be put back), as what the interpreter ran before an interrupt stays;
  // the scalars go back to their variables, and the interrupt is raised below.
  const bool interrupted = rc == kSystemInterrupted;
  // The binary32 copies of the vectors the call wrote go back (widened exactly), also when an
  // interrupt stopped it between iterations: what they hold then stays, as in place.
  if (rc == 0 || interrupted)
    for (size_t i = 0; i < b.arrays.size(); ++i) {
      if (!t.arrays[i].single || !t.arrays[i].written ||
          b.arrays[i].part != SystemBinding::Array::Part::Vector)
        continue;
      double* x = in.variable(*b.arrays[i].var).tensor().mutable_floats();
      const std::vector<float>& s = e->single[i];
      for (size_t k = 0; k < s.size(); ++k) x[k] = s[k];
    }
  if (rc != 0 && !interrupted) {
    for (auto& [var, value] : saved) in.variable(*var) = std::move(value);
    ++e->handed_back;
  }
  const std::vector<bool> written =
      interrupted ? scalars_written_up_to_loop(t) : std::vector<bool>();
  for (size_t i = 0; i < b.scalars.size() && (rc == 0 || interrupted); ++i) {
    if (!(interrupted ? written[i] : e->writes_scalar[i])) continue;
    switch (b.scalar_types[i]) {
      case Ty::F64: in.variable(*b.scalars[i]) = Value::of_float(scalars[i]); break;
      case Ty::I32:
        in.variable(*b.scalars[i]) = Value::of_int(static_cast<int32_t>(scalars[i]));
        break;
      case Ty::Bool: in.variable(*b.scalars[i]) = Value::of_bool(scalars[i] != 0.0); break;
    }
  }
  timer.done();
  e->stats.note = e->where;
  if (e->total > 0) {
    char note[160];
    std::snprintf(note, sizeof note,
                  "; products stream %.1f%% of the blocks (zero blocks dropped in %.2f cpu ms)",
                  100.0 * static_cast<double>(e->kept) / static_cast<double>(e->total),
                  e->prune_cpu_ms);
    e->stats.note += note;
  }
  e->stats.note += e->traffic.note();
  if (e->not_binary32 > 0)
    e->stats.note += "; " + std::to_string(e->not_binary32) + " call" +
                     (e->not_binary32 > 1 ? "s" : "") +
                     " ran interpreted: a matrix or vector held values that are not binary32";
  if (e->handed_back > 0)
    e->stats.note += "; " + std::to_string(e->handed_back) + " call" +
                     (e->handed_back > 1 ? "s" : "") +
                     " reached an error statement and ran again interpreted";
  if (e->kernel->cached) e->stats.note += "; from the kernel cache";
  if (interrupted) {
    // Taken and raised as the interpreter's trap point does (exec_trapped), at the statement
    // it would have stopped before: the REPL reports it and returns to its prompt.
    trap.take_interrupt();
    throw interp::Interrupted(interrupted_at(e->run).span, "interrupted");
  }
  return rc == 0;
}

}  // namespace simit::jit
