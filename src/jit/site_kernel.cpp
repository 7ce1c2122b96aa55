// A map site's kernel call: the site's arrays and scalars marshalled for its kernel, run
// through the executor, and a failed check reported as the interpreter reports it.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <functional>
#include <sstream>

#include "interp/exec_state.h"
#include "interp/runtime_error.h"
#include "interp/set_binding.h"
#include "jit/array_stamps.h"
#include "jit/controller_state.h"
#include "jit/matrix_sum.h"
#include "jit/pruned_matrix.h"
#include "jit/ptx/gpu_executor.h"
#include "jit/specialise.h"
#include "jit/write_guard.h"
#include "runtime/system_ops.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;

namespace {

// "mapping over element 5 of set 'tets' (endpoints 3, 9, 12, 40 of 'verts')", as the
// interpreter writes it: elements by their mesh numbers (a scene's renumbered mesh).
std::string element_note(const interp::SiteCall& call, int element) {
  const runtime::Set& t = call.target;
  const ast::Variable* target = call.plan.site->target_set;
  std::string note = "mapping over element " + std::to_string(t.mesh_number(element)) +
                     " of set '" + (target ? target->name : t.name()) + "'";
  if (element < 0 || element >= t.size() || t.arity() == 0) return note;
  std::string list;
  for (int k = 0; k < t.arity(); ++k)
    list += (k ? ", " : "") + std::to_string(t.endpoint_set(k).mesh_number(t.endpoint(element, k)));
  const bool one_set = t.homogeneous();
  return note + " (endpoints " + list + (one_set ? " of '" + t.endpoint_set(0).name() + "'" : "") +
         ")";
}

// Where each block a trace reads from a global matrix argument lies in its pattern, per
// element (-1 outside it). False where the interpreter must read it: a pattern that repeats
// blocks (they are summed) or a member outside the matrix's rows or columns (an error).
bool find_positions(const ArraySlot& a, const interp::SiteCall& call, std::vector<int32_t>& out) {
  const Value& v = call.partial_args[a.index];
  if (v.kind() != Value::Kind::Matrix || !v.matrix()) return false;
  const runtime::MatrixPattern& p = v.matrix()->pattern();
  if (!p.canonical()) return false;
  const runtime::Set& t = call.target;
  out.resize(static_cast<size_t>(t.size()) * a.reads.size());
  size_t k = 0;
  for (int e = 0; e < t.size(); ++e)
    for (const auto& [rm, cm] : a.reads) {
      const int32_t row = runtime::member_element(t, e, rm),
                    col = runtime::member_element(t, e, cm);
      if (row < 0 || row >= p.rows() || col < 0 || col >= p.cols()) return false;
      out[k++] = p.find(row, col);
    }
  return true;
}

// --jit-stats for a site on the GPU: what its last call copied to the device, found there
// already, zeroed there, set to -0.0 there and left there as the newest copy (in place of what an
// earlier call noted).
void note_traffic(std::string& note, const ptx::GpuTraffic& before, const ptx::GpuTraffic& after) {
  static const std::string kHead = "; last call to the device: ";
  if (const size_t at = note.find(kHead); at != std::string::npos) {
    const size_t end = note.find("; ", at + 2);
    note.erase(at, end == std::string::npos ? std::string::npos : end - at);
  }
  note += kHead + bytes_text(after.bytes_to_device - before.bytes_to_device) + " copied, " +
          bytes_text(after.bytes_skipped - before.bytes_skipped) + " there already, " +
          bytes_text(after.bytes_zeroed - before.bytes_zeroed) + " zeroed, " +
          bytes_text(after.bytes_filled - before.bytes_filled) + " set to -0.0, " +
          bytes_text(after.bytes_kept - before.bytes_kept) + " left there";
}

}  // namespace

double component(const Value& v, int i) {
  switch (v.kind()) {
    case Value::Kind::Float: return v.as_float();
    case Value::Kind::Int: return v.as_int();
    case Value::Kind::Bool: return v.as_bool() ? 1.0 : 0.0;
    case Value::Kind::Tensor: {
      const runtime::Tensor& t = v.tensor();
      switch (t.kind()) {
        case runtime::ComponentKind::Float: return t.floats()[i];
        case runtime::ComponentKind::Int: return t.ints()[i];
        case runtime::ComponentKind::Bool: return t.bools()[i] ? 1.0 : 0.0;
        default: return 0.0;
      }
    }
    default: return 0.0;
  }
}

void zero_results(interp::SiteCall& call) {
  for (Value& r : call.results) {
    if (r.kind() == Value::Kind::Matrix && r.matrix()) r.matrix()->set_zero();  // null: made later
    if (r.is_tensor()) {
      runtime::Tensor& t = r.tensor();
      if (t.kind() == runtime::ComponentKind::Float) t.fill(0, t.size(), 0.0);
    }
  }
}

// A deferred kernel's tables for this call (jit/deferred_plan.h): split into the executor's
// chunks, or in element order while the call records the blocks it writes (the marks need
// every write at its block) or when the topology does not allow a split. False when a
// result is not what the trace was made for (the interpreter then runs the site).
bool TraceController::prepare_deferred(Entry& e, interp::SiteCall& call,
                                       const std::vector<const int32_t*>& tables,
                                       const std::vector<runtime::PatternPtr>& patterns,
                                       int32_t chunk, MapWrites& writes) {
  const Trace& t = *e.traced.trace;
  std::vector<DeferredPlan::Source> sources(call.results.size());
  for (const ArraySlot& a : t.arrays) {
    if (a.kind != ArraySlot::Kind::Result) continue;
    DeferredPlan::Source& s = sources[static_cast<size_t>(a.index)];
    const Value& r = call.results[static_cast<size_t>(a.index)];
    s.components = a.components;
    if (r.kind() == Value::Kind::Matrix && r.matrix()) {
      s.table = tables[static_cast<size_t>(a.index)];
      s.pattern = patterns[static_cast<size_t>(a.index)];
      s.blocks = r.matrix()->pattern().nnz();
      if (!s.table) return false;
    } else if (r.is_tensor()) {
      s.blocks = r.tensor().size() / a.components;
    } else {
      return false;
    }
  }
  bool recording = false;
  for (const Entry::Special& s : e.special) recording = recording || !s.marks.empty();
  if (!e.plan) e.plan = std::make_unique<DeferredPlan>();
  const bool split = !recording && call.target.size() > chunk;
  writes = e.plan->prepare(t, call.target, sources, chunk, split) && split ? MapWrites::Deferred
                                                                           : MapWrites::Shared;
  if (writes == MapWrites::Deferred && !e.split_noted) {
    e.split_noted = true;
    e.stats.note += "; chunks of " + std::to_string(chunk) + " apart, " +
                    std::to_string(e.plan->deferred_blocks()) + " deferred blocks" +
                    (e.on_device ? " added on the device" : "");
  }
  return true;
}

bool TraceController::run_kernel(Entry& e, interp::SiteCall& call) {
  const Trace& t = *e.traced.trace;
  std::vector<double> scalars;
  for (const ScalarSource& s : e.traced.scalar_sources)
    scalars.push_back(component(
        s.partial >= 0 ? call.partial_args[s.partial] : call.interpreter.global(*s.global),
        s.component));
  // Under --float32 the kernel reads its float arguments as binary32 values, which is what
  // the program's own are (each an operator's rounded value); one the host bound wider
  // leaves the call to the interpreter.
  if (t.float32)
    for (size_t i = 0; i < scalars.size() && i < t.scalars.size(); ++i)
      if (t.scalars[i] == Ty::F64 && !runtime::is_binary32(scalars[i])) {
        if (e.not_binary32++ == 0)
          e.stats.note +=
              "; calls with a float argument that is not a binary32 value run "
              "interpreted";
        return false;
      }
  guard_results(e, call, scalars);
  std::vector<runtime::PatternPtr> patterns;
  const std::vector<const int32_t*> tables = prepare_results(e, call, &patterns);
  Executor& executor = e.on_device ? *device_executor_ : *executor_;
  const int32_t chunk = executor.chunk_for(call.target.size());
  MapWrites writes = e.writes;
  if (t.deferred && !prepare_deferred(e, call, tables, patterns, chunk, writes)) return false;
  std::vector<void*> arrays(t.arrays.size(), nullptr);
  // Each array's bytes and whether the kernel writes it, for an executor that copies them to
  // another memory (a GPU's).
  std::vector<size_t> bytes(t.arrays.size(), 0);
  std::vector<uint8_t> written(t.arrays.size(), 0);
  // For an executor that keeps copies between calls (the GPU's), each array's stamps and
  // what the host set it to for this call (MapArgs::array_version_in, array_fill). A
  // field's "in" before this call's own mutable access (which counts as a write), its "out"
  // after all of them.
  const bool resident = e.on_device;
  std::vector<uint64_t> version_in(t.arrays.size(), 0), version_out(t.arrays.size(), 0);
  std::vector<ArrayFill> fill(t.arrays.size(), ArrayFill::Copy);
  // Runtime arrays (fields, vectors, results, matrices): the device may keep what it wrote
  // until the host touches them (runtime/residency.h), and they are taken here without
  // bringing back a newer copy the device holds; on the host they are brought back.
  std::vector<uint8_t> runtime_array(t.arrays.size(), 0);
  auto field_slot_stamp = [&](const ArraySlot& a) {
    return field_stamp(runtime::member_set(call.target, a.member), a.index);
  };
  if (resident)
    for (size_t i = 0; i < t.arrays.size(); ++i)
      if (t.arrays[i].kind == ArraySlot::Kind::Field) version_in[i] = field_slot_stamp(t.arrays[i]);
  // Writable arrays first: taking one for writing may copy it (copy-on-write), and the
  // pointers read afterwards then see the copy.
  for (int pass = 0; pass < 2; ++pass)
    for (size_t i = 0; i < t.arrays.size(); ++i) {
      const ArraySlot& a = t.arrays[i];
      if (a.written != (pass == 0)) continue;
      written[i] = a.written ? 1 : 0;
      switch (a.kind) {
        case ArraySlot::Kind::Field: {
          auto& set = const_cast<runtime::Set&>(runtime::member_set(call.target, a.member));
          runtime::Field& f = set.field(a.index);
          if (resident)
            arrays[i] = a.written ? static_cast<void*>(f.raw_bytes())
                                  : const_cast<std::byte*>(std::as_const(f).raw_bytes());
          else
            arrays[i] = a.written ? static_cast<void*>(f.bytes())
                                  : const_cast<std::byte*>(std::as_const(f).bytes());
          runtime_array[i] = 1;
          bytes[i] = f.element_bytes() * static_cast<size_t>(set.size());
          break;
        }
        case ArraySlot::Kind::Vector: {
          const runtime::Tensor& v = call.partial_args[a.index].tensor();
          arrays[i] = const_cast<double*>(resident ? v.raw_floats() : v.floats());
          runtime_array[i] = v.shared_buffer() ? 1 : 0;  // inline storage moves with its value
          bytes[i] = static_cast<size_t>(v.size()) * sizeof(double);
          break;
        }
        case ArraySlot::Kind::Result: {
          Value& r = call.results[a.index];
          if (r.kind() == Value::Kind::Matrix) {
            runtime::SystemMatrix& m = *r.matrix();
            arrays[i] = resident ? m.raw_values() : m.values();
            runtime_array[i] = 1;
            bytes[i] = static_cast<size_t>(m.pattern().nnz()) *
                       static_cast<size_t>(m.block_size()) * sizeof(double);
          } else if (r.is_tensor()) {
            arrays[i] = resident ? r.tensor().raw_mutable_floats() : r.tensor().mutable_floats();
            runtime_array[i] = r.tensor().shared_buffer() ? 1 : 0;
            bytes[i] = static_cast<size_t>(r.tensor().size()) * sizeof(double);
          } else {
            return false;
          }
          // The interpreter's results and prepare_results' are zeroed.
          fill[i] = ArrayFill::Zero;
          break;
        }
        case ArraySlot::Kind::Table: {
          const int32_t* table = e.plan ? e.plan->table(a.index) : nullptr;
          arrays[i] = const_cast<int32_t*>(table ? table : tables[a.index]);
          const auto& full = call.plan.results[static_cast<size_t>(a.index)].pattern;
          bytes[i] = (table ? e.plan->table_entries(a.index)
                            : (full ? full->assembly().table.size() : 0)) *
                     sizeof(int32_t);
          if (!resident) break;
          // A split table: named by the plan's build; a pattern's table (full, or
          // specialised: the full pattern's positions in the specialised one): by the
          // patterns; a vector result's member table of an unsplit call: unknown.
          if (table && writes == MapWrites::Deferred)
            version_in[i] =
                stamp(StampKind::Split, {e.plan->build_id(), static_cast<uint64_t>(a.index)});
          else if (arrays[i] == tables[a.index] && full &&
                   tables[a.index] == full->assembly().table.data())
            version_in[i] = stamp(StampKind::Pattern, {pattern_number(full)});
          else if (arrays[i] == tables[a.index] && full && patterns[a.index])
            version_in[i] = stamp(StampKind::Specialised,
                                  {pattern_number(full), pattern_number(patterns[a.index])});
          version_out[i] = version_in[i];
          break;
        }
        case ArraySlot::Kind::Deferred:
          arrays[i] = e.plan->deferred(a.index);
          bytes[i] = e.plan->deferred_values(a.index) * sizeof(double);
          // DeferredPlan::prepare of a split run leaves every deferred block of every result
          // it writes at -0.0 (built so, or reset); an unsplit run's are not reset (its
          // kernel adds nothing there but into the sink, which no gather reads): copied.
          if (writes == MapWrites::Deferred) fill[i] = ArrayFill::NegativeZero;
          break;
        case ArraySlot::Kind::Marks: {
          const size_t r = static_cast<size_t>(a.index);
          arrays[i] = r < e.special.size() && !e.special[r].marks.empty()
                          ? e.special[r].marks.data()
                          : nullptr;
          bytes[i] = arrays[i] ? e.special[r].marks.size() : 0;
          break;
        }
        case ArraySlot::Kind::Matrix: {
          const Value& m = call.partial_args[a.index];
          if (m.kind() != Value::Kind::Matrix || !m.matrix()) return false;
          arrays[i] =
              const_cast<double*>(resident ? m.matrix()->raw_values() : m.matrix()->values());
          runtime_array[i] = 1;
          bytes[i] = static_cast<size_t>(m.matrix()->pattern().nnz()) *
                     static_cast<size_t>(m.matrix()->block_size()) * sizeof(double);
          break;
        }
        case ArraySlot::Kind::Positions:
          e.positions.resize(t.arrays.size());
          if (!find_positions(a, call, e.positions[i])) return false;
          arrays[i] = e.positions[i].data();
          bytes[i] = e.positions[i].size() * sizeof(int32_t);
          break;
      }
    }
  MapArgs args{arrays.data(), scalars.data(), call.target.endpoints()};
  args.array_count = arrays.size();
  args.array_bytes = bytes.data();
  args.array_written = written.data();
  args.scalar_count = scalars.size();
  args.arity = call.target.arity();
  if (resident) {
    for (size_t i = 0; i < t.arrays.size(); ++i)
      if (t.arrays[i].kind == ArraySlot::Kind::Field)
        version_out[i] = field_slot_stamp(t.arrays[i]);
    args.array_version_in = version_in.data();
    args.array_version_out = version_out.data();
    args.array_fill = fill.data();
    args.endpoints_version = endpoints_stamp(call.target);
    args.array_resident = runtime_array.data();
  }
  const ptx::GpuTraffic before = resident ? ptx::gpu_traffic(executor) : ptx::GpuTraffic{};
  interp::Trap& trap = call.interpreter.trap();
  const MapOutcome out = executor.run_map(*e.kernel, args, call.target.size(), chunk, writes,
                                          [&trap] { return trap.interrupt_pending(); });
  if (out.code != 0) {
    const ErrorSite& err = t.errors[static_cast<size_t>(out.code - 1)];
    for (Entry::Special& s : e.special) s.marks.clear();  // this call records nothing
    if (!t.writes_fields) {
      // Nothing but the results changed: the interpreter runs the site again from zero
      // and reports the error in its own words, with its call stack (on full patterns).
      for (size_t i = 0; i < call.results.size(); ++i)
        if (call.plan.results[i].is_matrix && call.results[i].matrix() &&
            call.results[i].matrix()->shared_pattern() != call.plan.results[i].pattern)
          call.results[i] = Value::of_matrix(nullptr);
      zero_results(call);
      return false;
    }
    // Located as the interpreter locates it: the mapped function's frame names the element.
    interp::RuntimeError error(err.span, err.message);
    for (const auto& [callee, at] : err.frames) error.add_frame(callee, at);
    error.add_frame(call.plan.func->name, call.at);
    error.note_element(call.plan.func->name, element_note(call, out.element));
    throw error;
  }
  if (out.interrupted) {
    trap.take_interrupt();
    throw interp::Interrupted(call.at, "interrupted");
  }
  if (writes == MapWrites::Deferred) {
    std::vector<double*> values(call.results.size(), nullptr);
    for (size_t i = 0; i < call.results.size(); ++i) {
      Value& r = call.results[i];
      if (r.kind() == Value::Kind::Matrix && r.matrix())
        values[i] = resident ? r.matrix()->raw_values() : r.matrix()->values();
      else if (r.is_tensor() && r.tensor().kind() == runtime::ComponentKind::Float)
        values[i] = resident ? r.tensor().raw_mutable_floats() : r.tensor().mutable_floats();
    }
    executor.finish_deferred(*e.plan, values);
  }
  if (resident) note_traffic(e.stats.note, before, ptx::gpu_traffic(executor));
  specialise_results(e, call);
  return true;
}

}  // namespace simit::jit
