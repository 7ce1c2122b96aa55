// Random Simit programs, generated from a seed, run through the interpreter and the tracing JIT
// (threshold 0) and compared bit for bit (up to the sign of a zero): every result of the exported
// function and every field of every set, after each of several calls. SIMIT_RANDOM_PROGRAMS=N runs
// N programs, from SIMIT_RANDOM_SEED (default 1); SIMIT_RANDOM_PRINT=1 prints each program and its
// traces. SIMIT_TEST_GPU=1 compares the GPU executor on a real GPU instead of the JIT (and fails
// where none can run); SIMIT_TEST_GPU_EMULATION=1 the GPU executor over host memory.
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
#include <string_view>
#include <vector>

#include "api/engine.h"
#include "interp/runtime_error.h"
#include "jit/tunables.h"
#include "random_program_gen.h"

namespace simit::jit {
namespace {

using namespace random_programs;
using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;
using interp::Value;

// Programs per run unless SIMIT_RANDOM_PROGRAMS says otherwise: a few hundred fit in CI.
constexpr long kDefaultPrograms = 240;

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
    if (set.field_count() == 0 || element < 0) return;
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
      // An empty set has no element to rewrite (pick(0, -1) is -1).
      rewrite(w.verts, w.verts.size() ? pick(0, w.verts.size() - 1) : -1);
      rewrite(*w.edges, w.edges->size() ? pick(0, w.edges->size() - 1) : -1);
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
    o.executor.kind = kind;
    o.executor.threshold = 0;
    // One thread unless SIMIT_TEST_THREADS says (ctest runs them on 3, in chunks of a few
    // elements: SIMIT_TEST_THREAD_CHUNK).
    const char* threads = std::getenv("SIMIT_TEST_THREADS");
    o.executor.threads = threads && *threads ? std::atoi(threads) : 1;
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

// Whether a float field of the set holds an infinity or a NaN.
bool non_finite(const runtime::Set& s) {
  for (int f = 0; f < s.field_count(); ++f) {
    const runtime::Field& x = s.field(f);
    if (x.type().kind != runtime::ComponentKind::Float) continue;
    const size_t n = static_cast<size_t>(s.size()) * x.components();
    for (size_t i = 0; i < n; ++i)
      if (!std::isfinite(x.type().single ? x.data<float>()[i] : x.data<double>()[i])) return true;
  }
  return false;
}

// What the JIT did with a program's sites and loops, from print_jit_stats.
struct Tally {
  int programs = 0, runtime_errors = 0, nans = 0;
  // Programs whose fields held an infinity or a NaN before a call: compared no further.
  int non_finite_inputs = 0;
  // Programs on an empty vertex or edge set, with a chain of helpers past the inline depth.
  int empty_sets = 0, deep_chains = 0;
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
      auto ends = [&](const std::string& tail) {
        return l.size() >= tail.size() && l.compare(l.size() - tail.size(), tail.size(), tail) == 0;
      };
      if (ends(" compiled") || ends(" compiled for the GPU")) {
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
std::string check_program(uint64_t seed, ExecutorKind compiled, Tally& tally) {
  const Generated g = generate_program(seed);
  const auto program = CompiledProgram::from_source("random.sim", g.text);
  if (!program->ok())
    return "the generator made a program that does not check (a generator bug):\n" + g.text + "\n" +
           program->compilation()->diagnostics.render_all();
  if (env_long("SIMIT_RANDOM_PRINT", 0))
    std::printf("--- seed %llu ---\n%s", static_cast<unsigned long long>(seed), g.text.c_str());
  Runner in(program, g, ExecutorKind::Interpreter), jit(program, g, compiled);
  ++tally.programs;
  tally.empty_sets += g.sets.verts == 0 || g.sets.edges == 0;
  tally.deep_chains += g.chain_depth > kMaxInlineDepth;
  std::string diff;
  for (int call = 0; call < 3 && diff.empty(); ++call) {
    // A product by a vector that holds an infinity or a NaN may give a number in the JIT
    // where the interpreter's zero block gives NaN (a compiled loop's copy of a matrix drops
    // its zero blocks, a specialised pattern leaves them out: docs/jit.md), and a loop's
    // condition may then differ: such inputs end the comparison.
    if (call > 0 && (non_finite(in.world.verts) || non_finite(*in.world.edges))) {
      ++tally.non_finite_inputs;
      break;
    }
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

bool env_flag(const char* name) {
  const char* v = std::getenv(name);
  return v && *v && std::string_view(v) != "0";
}

TEST(RandomPrograms, TheJitComputesTheInterpretersBits) {
  // SIMIT_TEST_GPU asks for a GPU: where none can run, that is a failure, not a skip (the GPU
  // check would otherwise report a pass that compared nothing on a GPU).
  const bool on_gpu = env_flag("SIMIT_TEST_GPU");
  if (on_gpu) {
    const std::string why =
        simit::executor_unavailable(simit::ExecutorChoice{.kind = ExecutorKind::Gpu});
    if (!why.empty())
      FAIL() << "SIMIT_TEST_GPU=1 asks for the GPU executor, which cannot run: " << why;
  }
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  // SIMIT_TEST_GPU_EMULATION without SIMIT_TEST_GPU: the GPU executor over host memory.
  const bool emulated = simit::gpu_emulated_for_test();
  const ExecutorKind compiled = on_gpu || emulated ? ExecutorKind::Gpu : ExecutorKind::Jit;
  std::printf("compared with the interpreter: the %s executor%s\n", executor_name(compiled),
              compiled != ExecutorKind::Gpu ? ""
              : emulated                    ? " (emulated over host memory)"
                                            : " (on the GPU)");
  const long count = env_long("SIMIT_RANDOM_PROGRAMS", kDefaultPrograms);
  const uint64_t first = static_cast<uint64_t>(env_long("SIMIT_RANDOM_SEED", 1));
  Tally tally;
  int failures = 0;
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i < count && failures < 3; ++i) {
    const std::string report = check_program(first + static_cast<uint64_t>(i), compiled, tally);
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
      "programs on an empty set: %d; with a call chain past the inline depth: %d; "
      "compared no further after a call left an infinity or a NaN in a field: %d\n",
      tally.empty_sets, tally.deep_chains, tally.non_finite_inputs);
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
