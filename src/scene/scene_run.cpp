// Running a scene: bindings checked and made once, init, the frames, the output.
#include "scene/scene_run.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>
#include <type_traits>
#include <vector>

#include "api/stop_on_sigint.h"
#include "runtime/fault.h"
#include "scene/progress.h"

namespace simit::scene {

namespace ast = frontend::ast;
using runtime::ComponentKind;

void SceneRun::build() {
  tensors_ = read_tensors(file_, options_.float32);
  // A distributed run: rank 0 alone reads the meshes and builds the whole sets; every rank
  // then receives its part from it (localize).
  if (options_.distributed && options_.distributed->rank() != 0) {
    try {
      sets_ = declared_sets(file_, meshes_);
    } catch (const SceneError&) {
      options_.distributed->wait_for_abort();  // rank 0 meets it too, and reports it
    }
  } else
    sets_ = build_sets(file_, meshes_, options_.float32, reorder_);
  if (options_.distributed) localize();
}

std::vector<runtime::Set*> SceneRun::whole_sets() const {
  std::vector<runtime::Set*> whole;
  for (const auto& s : sets_.sets) whole.push_back(s->set.get());
  return whole;
}

// Rank 0 built the whole sets: every rank receives its part to run on.
void SceneRun::localize() {
  if (options_.executor.kind == ExecutorKind::Gpu) {
    if (options_.distributed->rank() != 0) options_.distributed->wait_for_abort();
    throw SceneError(file_.path +
                     ": error: --distributed runs the interpreter or the JIT (executor gpu is "
                     "not distributed yet)");
  }
  try {
    local_ = options_.distributed->localize(whole_sets());
  } catch (const std::runtime_error& e) {
    throw SceneError(file_.path + ": error: --distributed: " + e.what());
  }
}

std::vector<runtime::Set*> SceneRun::local_sets() const {
  std::vector<runtime::Set*> local;
  for (const auto& s : local_) local.push_back(s.get());
  return local;
}

// Rank 0's whole sets are read for the last frame (the picture, --final-csv) and, on one
// rank, for every frame written (one .vtu a frame); several ranks write pieces instead.
void SceneRun::gather(bool last) const {
  if (options_.distributed && (last || !pieces_))
    options_.distributed->gather(local_sets(), whole_sets());
}

// Rank 0 checked [output]: it tells the others what their pieces hold.
void SceneRun::start_pieces() {
  const Distributed& d = *options_.distributed;
  std::string text =
      d.rank() == 0 && output_.writes_frames() ? PieceSeries::encode(output_.piece_settings()) : "";
  d.broadcast(text);
  if (text.empty()) return;
  PieceSeries::Settings settings = PieceSeries::decode(text);
  const runtime::Set* points = nullptr;
  const runtime::Set* cells = nullptr;
  for (size_t k = 0; k < sets_.sets.size() && k < local_.size(); ++k) {
    if (sets_.sets[k]->name == settings.points) points = local_[k].get();
    if (sets_.sets[k]->name == settings.cells) cells = local_[k].get();
  }
  if (!points) return;
  std::vector<int32_t> owned_cells;
  if (cells) {
    const std::vector<int32_t>* owned = d.owned(*cells);
    if (owned) {
      owned_cells = *owned;
    } else {
      owned_cells.resize(static_cast<size_t>(cells->size()));
      std::iota(owned_cells.begin(), owned_cells.end(), 0);
    }
  }
  pieces_.emplace(std::move(settings), d.rank(), *points, cells, std::move(owned_cells));
  if (d.rank() == 0) output_.join_pieces(d.ranks());
}

// Every rank's piece of a frame the series writes, all of them there before rank 0's .pvtu.
void SceneRun::write_pieces(int frame, bool last) {
  if (!pieces_ || !(pieces_->every_frame(frame) || last)) return;
  pieces_->write();
  options_.distributed->any(false);
}

// Everything `name` (the scene's `key` procedure) uses must be bound by the scene.
void SceneRun::check_needs(const std::string& key, const std::string& name) const {
  const ast::FuncDecl& f = *file_.program->find_func(name);
  for (const ast::Variable* g : f.extern_uses) {
    if (sets_.by_name.count(g->name) || tensors_.count(g->name)) continue;
    if (g->type && g->type->is_tensor())
      file_.fail(file_.doc.get(key), key + ": '" + name + "' uses the extern tensor '" + g->name +
                                         "' (" + frontend::to_string(*g->type) +
                                         "), which is not set: add it to [tensors]");
    file_.fail(file_.doc.get(key),
               key + ": '" + name + "' needs '" + g->name + "' bound, which a scene cannot bind");
  }
}

// Sets (vertex sets first: edge sets refer to their endpoints' bindings) and tensors, once.
void SceneRun::bind(api::Engine& engine) const {
  try {
    for (int pass = 0; pass < 2; ++pass)
      for (size_t k = 0; k < sets_.sets.size(); ++k) {
        const SceneSet& s = *sets_.sets[k];
        runtime::Set& set = local_.empty() ? *s.set : *local_[k];
        if ((set.arity() == 0) == (pass == 0)) engine.bind_set(*s.var, set);
      }
    for (const auto& [name, t] : tensors_) engine.set_global(*t.var, t.value);
  } catch (const interp::RuntimeError& e) {
    throw SceneError(file_.path + ": error: " + e.message());
  }
}

// Runs the procedure `name`; a run-time error becomes a RunFailure with its full message.
std::vector<interp::Value> SceneRun::call(api::Engine& engine, const std::string& name) {
  try {
    // SceneOptions::stop_on_interrupt: Ctrl-C stops this call (the host goes on after it).
    std::optional<api::StopOnSigint> stop_on_sigint;
    if (options_.stop_on_interrupt && !trap_ && !options_.jit_stats) {
      own_trap_.take_interrupt();  // one that came between two calls
      stop_on_sigint.emplace(own_trap_);
    }
    return engine.call(*file_.program->find_func(name), {});
  } catch (const interp::Interrupted& e) {
    own_trap_.take_interrupt();
    throw RunFailure(e.render(), e.line(), true);
  } catch (const interp::RuntimeError& e) {
    throw RunFailure(e.render(), e.line());
  } catch (const runtime::Fault& e) {
    throw RunFailure(std::string("runtime error: ") + e.what());
  }
}

// The results of step named in file_.stat_names, as numbers.
std::vector<double> SceneRun::step_stats(const std::vector<interp::Value>& results) const {
  const ast::FuncDecl& step = *file_.program->find_func(file_.step_name);
  std::vector<double> stats;
  for (size_t i = 0; i < step.results.size(); ++i) {
    const std::vector<std::string>& names = file_.stat_names;
    if (std::find(names.begin(), names.end(), step.results[i].name) == names.end()) continue;
    runtime::Tensor v = results.at(i).to_tensor();
    switch (v.kind()) {
      case ComponentKind::Int: stats.push_back(v.ints()[0]); break;
      case ComponentKind::Bool: stats.push_back(v.bools()[0]); break;
      case ComponentKind::Float: stats.push_back(v.floats()[0]); break;
      default: stats.push_back(NAN); break;
    }
  }
  return stats;
}

void SceneRun::print_sizes(std::ostream& out, int frames) const {
  std::string sizes;
  for (const auto& s : sets_.sets)
    if (s->set)  // not on a distributed run's ranks other than 0
      sizes += (sizes.empty() ? "" : ", ") + s->name + " " + std::to_string(s->set->size());
  out << file_.path << ": " << sizes << "; " << frames << " frames\n";
}

namespace {

// Whether any of the n values is a NaN or an infinity (its exponent bits all set): one pass
// without a branch per value, which vectorises; the usual frame has none.
template <typename T>
bool any_non_finite(const T* p, size_t n) {
  using Bits = std::conditional_t<sizeof(T) == 8, uint64_t, uint32_t>;
  constexpr Bits kExponent = sizeof(T) == 8 ? Bits{0x7ff} << 52 : Bits{0xff} << 23;
  Bits any = 0;
  for (size_t i = 0; i < n; ++i) any |= (std::bit_cast<Bits>(p[i]) & kExponent) == kExponent;
  return any != 0;
}

// The first non-finite component of a float field among the first `elements` of `set` in the
// mesh's order (the element of least mesh number, then its first such component): element and
// component, or -1.
template <typename T>
std::pair<int, int> first_non_finite(const runtime::Set& set, const runtime::Field& f,
                                     const std::vector<int32_t>* elements) {
  const T* p = f.data<T>();
  const size_t components = f.components();
  const size_t count = elements ? elements->size() : static_cast<size_t>(set.size());
  std::pair<int, int> first = {-1, -1};
  if (!elements && !any_non_finite(p, count * components)) return first;
  for (size_t n = 0; n < count; ++n) {
    const int element = elements ? (*elements)[n] : static_cast<int>(n);
    for (size_t c = 0; c < components; ++c) {
      if (std::isfinite(p[static_cast<size_t>(element) * components + c])) continue;
      if (first.first < 0 || set.mesh_number(element) < set.mesh_number(first.first))
        first = {element, static_cast<int>(c)};
      break;  // the element's later components come after
    }
    if (first.first >= 0 && !set.has_mesh_numbers()) break;
  }
  return first;
}

std::string number_text(double v) { return std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf"; }

}  // namespace

// The default check at frame boundaries: one pass over the float fields of every set and the
// step's float results, so that a NaN or an infinity stops the run at the frame that made it
// instead of filling the rest of the series. Frame 0 is the state after init.
void SceneRun::check_finite_state(int frame, const std::vector<interp::Value>& results) const {
  if (!options_.finite_check || !file_.finite_check) return;
  const std::string when = frame > 0                 ? "after frame " + std::to_string(frame)
                           : file_.init_name.empty() ? "in the initial state (frame 0)"
                                                     : "after init (frame 0)";
  const std::string hint =
      " (--check-finite stops at the statement that makes it; --no-finite-check lets it through)";
  // Per set and float field, in order: the first non-finite element. A distributed run's ranks
  // each look at the elements they own; the least mesh number over the ranks wins, and the
  // rank that owns it reports it (the others wait for its abort), as one process would.
  const Distributed* ranks = options_.distributed.get();
  struct Found {
    const runtime::Set* set;
    const std::string* name;
    int field, element, component;
  };
  std::vector<Found> found;
  std::vector<int64_t> least;
  for (size_t k = 0; k < sets_.sets.size(); ++k) {
    const runtime::Set& set = ranks ? *local_[k] : *sets_.sets[k]->set;
    const std::vector<int32_t>* elements = ranks ? ranks->owned(set) : nullptr;
    for (int i = 0; i < set.field_count(); ++i) {
      const runtime::Field& f = set.field(i);
      if (f.type().kind != ComponentKind::Float) continue;
      auto [element, component] = f.type().single ? first_non_finite<float>(set, f, elements)
                                                  : first_non_finite<double>(set, f, elements);
      found.push_back({&set, &sets_.sets[k]->name, i, element, component});
      least.push_back(element < 0 ? INT64_MAX : set.mesh_number(element));
    }
  }
  if (ranks) ranks->least(least);
  for (size_t i = 0; i < found.size(); ++i) {
    if (least[i] == INT64_MAX) continue;
    const Found& x = found[i];
    if (ranks && (x.element < 0 || x.set->mesh_number(x.element) != least[i]))
      ranks->wait_for_abort();  // another rank owns it
    const runtime::Field& f = x.set->field(x.field);
    const size_t at = static_cast<size_t>(x.element) * f.components() + x.component;
    const double v = f.type().single ? f.data<float>()[at] : f.data<double>()[at];
    const std::string part =
        f.components() > 1 ? " (component " + std::to_string(x.component) + ")" : "";
    throw RunFailure(file_.path + ": error: " + when + ": field '" + f.name() + "' of element " +
                     std::to_string(least[i]) + " of set '" + *x.name + "' is " + number_text(v) +
                     part + hint);
  }
  // The step's results are the same on every rank: rank 0 reports them.
  const std::vector<ast::Param>& declared = file_.program->find_func(file_.step_name)->results;
  for (size_t i = 0; i < results.size() && i < declared.size(); ++i) {
    const runtime::Tensor v = results[i].to_tensor();
    if (v.kind() != ComponentKind::Float) continue;
    for (size_t c = 0; c < v.size(); ++c)
      if (!std::isfinite(v.floats()[c])) {
        if (ranks && ranks->rank() != 0) ranks->wait_for_abort();
        throw RunFailure(file_.path + ": error: " + when + ": the result '" + declared[i].name +
                         "' of " + file_.step_name + " is " + number_text(v.floats()[c]) + hint);
      }
  }
}

api::EngineOptions SceneRun::engine_options(std::ostream& out) const {
  api::EngineOptions eo;
  eo.float32 = options_.float32;
  eo.check_finite = options_.check_finite;
  eo.out = &out;
  eo.trap = trap_;
  if (!trap_ && (options_.jit_stats || options_.stop_on_interrupt)) eo.trap = &own_trap_;
  eo.executor =
      options_.executor;  // resolved with the scene file's keys and checked by Scene::open
  eo.dump = &out;
  eo.distribution = options_.distributed.get();
  // The run reads fields for its output and checks through their accessors; a stepper's host
  // holds views of them (pinned sets), which must be current whenever a call returns.
  eo.host_uses_accessors = std::none_of(sets_.sets.begin(), sets_.sets.end(), [](const auto& s) {
    return s->set && s->set->fields_pinned();
  });
  return eo;
}

void SceneRun::prepare(std::ostream& out) {
  if (!options_.quiet) output_.configure(sets_);
  if (!file_.init_name.empty()) check_needs("init", file_.init_name);
  check_needs("step", file_.step_name);
  engine_ = std::make_unique<api::Engine>(file_.program, engine_options(out));
  bind(*engine_);
  output_.open(file_.stat_names);
  // A host that steps the scene finds each frame's files written when step() returns, unless
  // [output] background = true; run() decides by the cores (below).
  output_.write_in_background(false);
  if (options_.distributed && options_.distributed->ranks() > 1) start_pieces();
}

void SceneRun::initialise(bool last) {
  if (!file_.init_name.empty()) call(*engine_, file_.init_name);
  gather(last);
  check_finite_state(0, {});
  write_pieces(0, last);
  output_.write_frame(meshes_, 0, last);
  last_written_ = 0;
}

FrameResult SceneRun::frame(int frame, bool last) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  engine_->reset_stats();
  FrameResult r;
  r.results = call(*engine_, file_.step_name);
  r.ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  r.assembly_ms = std::min(r.ms, 1e3 * engine_->stats().assembly_seconds);
  r.stats = step_stats(r.results);
  gather(last);
  check_finite_state(frame, r.results);
  write_pieces(frame, last);
  if (output_.every_frame(frame) || last) {
    output_.write_frame(meshes_, frame, last);
    last_written_ = frame;
  }
  output_.write_stats(frame, r.ms, r.stats, r.assembly_ms);
  return r;
}

void SceneRun::finish(int last_frame) {
  // A run that stops where it likes: its last frame joins the series unless it is there.
  if (last_written_ != last_frame)
    output_.write_frame(meshes_, last_frame, true);
  else
    output_.write_picture();
  last_written_ = last_frame;
  output_.write_final_csv();
}

const ast::FuncDecl& SceneRun::step_function() const {
  return *file_.program->find_func(file_.step_name);
}

void SceneRun::run(int frames, std::ostream& out) {
  // --jit-stats: Ctrl-C stops the run with an error instead of ending the process, so that
  // the stats still print (the debugger's trap stops it its own way).
  std::optional<api::StopOnSigint> stop_on_sigint;
  if (options_.jit_stats && !trap_) stop_on_sigint.emplace(own_trap_);
  prepare(out);
  print_sizes(out, frames);
  if (options_.distributed) out << options_.distributed->describe_parts(local_sets());
  // Everything is checked: run. Where the run leaves a core to spare, each frame is written
  // on it while the next one computes (scene/frame_writer.h), unless [output] background says
  // otherwise. Where every core computes, the writer would take time from the threads of the
  // next frame (the fem bunny's compiled frame on both cores of a 2-core machine: 3.2 ms,
  // 3.6-3.8 with its frames written beside it).
  const int computing = options_.executor.kind == ExecutorKind::Gpu ? 0
                        : options_.executor.kind == ExecutorKind::Interpreter
                            ? 1
                            : options_.executor.threads;
  output_.write_in_background(computing < default_threads());  // the cores it may use
  double total_ms = 0;
  try {
    initialise(frames == 0);
    total_ms = run_frames(frames, out);
    output_.finish_writing();
  } catch (...) {
    // The frames before the one the run stops at are on disk before it says why.
    output_.finish_writing_quietly();
    throw;
  }
  if (options_.progress_line && frames > 0) out << '\n';
  print_summary(out, frames, total_ms, options_.quiet, output_.pvd_path());
  if (options_.distributed) out << options_.distributed->describe_traffic();
  print_jit_stats(out);
  output_.write_final_csv();
}

void SceneRun::print_jit_stats(std::ostream& out) {
  if (!options_.jit_stats || !engine_ || jit_stats_printed_) return;
  jit_stats_printed_ = true;
  engine_->print_jit_stats(out);
}

// Frames 1 .. frames: step, the output, the progress. Returns the frames' total ms.
double SceneRun::run_frames(int frames, std::ostream& out) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  double total_ms = 0.0;
  for (int n = 1; n <= frames; ++n) {
    const FrameResult r = frame(n, n == frames);
    total_ms += r.ms;
    if (options_.quiet) continue;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    print_progress(out,
                   FrameReport{n, frames, r.ms, total_ms, elapsed, &file_.stat_names, &r.stats},
                   options_.progress_line);
  }
  return total_ms;
}

}  // namespace simit::scene
