// Times the interpreter assembling the Neo-Hookean stiffness matrix of a TetGen mesh
// (bench/programs/neohookean_stiffness.sim): N assemblies, reported in ms per assembly, then
// one more assembly under a statement hook that splits the time into element computation,
// scatter and map overhead, and the matrix's memory (values, pattern).
//
// Usage: assembly_bench MESH.node [N] [program.sim]
//
// How the split is measured: a StatementHook (interp/hook.h) reads a steady clock before
// every statement and charges the interval since the previous statement to that statement's
// category. Scatter statements are the assignments whose target indexes the mapped
// function's matrix result (`K(v(a), v(b)) = Kab;`, right-hand side a local, so their time
// is index evaluation, block lookup in the precomputed assembly index and the 9 adds).
// Every other statement of the mapped function and of the functions it calls is element
// computation. The interval that ends at the first statement of the mapped function holds
// the last scatter statement of the previous element plus the map's per-element overhead
// (frame setup); it is counted as scatter and its average is printed beside that of the other
// scatter statements, so the overhead can be read off. Hooked runs are slower than plain runs
// (a virtual call and two clock reads per statement). The hook's body lies between its two
// clock reads and so in no phase; whatever the phases' sum exceeds the plain time by is
// subtracted from each phase per statement, and both raw and corrected splits are printed.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "api/engine.h"
#include "interp/hook.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/set.h"

namespace {

namespace ast = simit::frontend::ast;
using simit::interp::Value;
using Clock = std::chrono::steady_clock;

class PhaseTimer : public simit::interp::StatementHook {
 public:
  enum Phase { None, Driver, Element, Scatter, Boundary, Phases };

  explicit PhaseTimer(const ast::FuncDecl& element) : element_(element) {}

  void before_statement(const ast::Stmt& stmt, const ast::FuncDecl& func, int depth,
                        const simit::interp::Interpreter&) override {
    const Clock::time_point now = Clock::now();
    Phase next = classify(stmt, func, depth);
    if (current_ != None) {
      // The interval ending at the mapped function's first statement spans the previous
      // element's last statement and the map's per-element overhead.
      const bool boundary = &func == &element_ && !element_.body.empty() &&
                            &stmt == element_.body.front().get() && current_ != Driver;
      seconds_[boundary ? Boundary : current_] +=
          std::chrono::duration<double>(now - last_).count();
      ++count_[boundary ? Boundary : current_];
    }
    current_ = next;
    last_ = Clock::now();
  }
  void reset() {
    current_ = None;
    for (int p = 0; p < Phases; ++p) seconds_[p] = 0.0, count_[p] = 0;
  }
  void stop() {
    if (current_ != None)
      seconds_[current_] += std::chrono::duration<double>(Clock::now() - last_).count();
    current_ = None;
  }
  double seconds(Phase p) const { return seconds_[p]; }
  long count(Phase p) const { return count_[p]; }

 private:
  Phase classify(const ast::Stmt& stmt, const ast::FuncDecl& func, int depth) const {
    if (depth == 0) return Driver;
    if (&func == &element_) {
      if (const auto* a = stmt.as<ast::Assign>(); a && a->targets.size() == 1) {
        if (const auto* r = a->targets[0]->as<ast::TensorRead>())
          if (const auto* v = r->base->as<ast::VarRef>();
              v && v->var && v->var->kind == ast::Variable::Kind::Result)
            return Scatter;
      }
    }
    return Element;
  }

  const ast::FuncDecl& element_;
  Phase current_ = None;
  Clock::time_point last_;
  double seconds_[Phases] = {};
  long count_[Phases] = {};
};

void add_fields(const ast::Variable& v, simit::runtime::Set& s) {
  for (const ast::FieldDecl& f : v.type->element->fields)
    if (s.field_index(f.name) < 0) s.add_field(f.name, simit::interp::field_type_of(*f.type));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: assembly_bench MESH.node [assemblies] [program.sim]\n");
    return 2;
  }
  const std::string mesh_path = argv[1];
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 3;
  const std::string program_path =
      argc > 3 ? argv[3] : SIMIT_SOURCE_DIR "/bench/programs/neohookean_stiffness.sim";

  auto c = simit::api::CompiledProgram::from_file(program_path);
  if (!c->ok()) {
    std::fputs(c->compilation()->diagnostics.render_all().c_str(), stderr);
    return 1;
  }
  const ast::FuncDecl* stiffness = c->find_func("stiffness");
  const ast::FuncDecl* element = c->find_func("tet_stiffness");
  const ast::Variable *verts_var = nullptr, *tets_var = nullptr;
  for (const ast::Variable* v : c->program().globals) {
    if (v && v->name == "verts") verts_var = v;
    if (v && v->name == "tets") tets_var = v;
  }
  if (!stiffness || !element || !verts_var || !tets_var) {
    std::fprintf(stderr, "%s lacks stiffness, tet_stiffness, verts or tets\n",
                 program_path.c_str());
    return 1;
  }

  auto t0 = Clock::now();
  simit::runtime::Mesh mesh = simit::runtime::read_mesh(mesh_path);
  simit::runtime::Set verts("verts"), tets("tets", {&verts, &verts, &verts, &verts});
  verts.add_many(static_cast<int>(mesh.points.size()));
  std::vector<int32_t> flat;
  flat.reserve(mesh.tets.size() * 4);
  for (const auto& t : mesh.tets) flat.insert(flat.end(), t.begin(), t.end());
  tets.add_edges(flat);
  add_fields(*verts_var, verts);
  add_fields(*tets_var, tets);
  double* X = verts.field("X").data<double>();
  double* x = verts.field("x").data<double>();
  for (size_t i = 0; i < mesh.points.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      X[3 * i + k] = mesh.points[i][k];
      // A smooth deformation: stretch and shear, so that every element is loaded.
      x[3 * i + k] = mesh.points[i][k] * (1.0 + 0.02 * k) + 0.01 * mesh.points[i][(k + 1) % 3];
    }
  double* mu = tets.field("mu").data<double>();
  double* lambda = tets.field("lambda").data<double>();
  for (int e = 0; e < tets.size(); ++e) {
    mu[e] = 3.5e5;
    lambda[e] = 1.2e6;
  }
  const double load_s = std::chrono::duration<double>(Clock::now() - t0).count();
  std::printf("mesh %s: %d vertices, %d tets (read and sets built in %.0f ms)\n", mesh_path.c_str(),
              verts.size(), tets.size(), 1e3 * load_s);

  // Plain runs.
  simit::api::Engine interp(c);
  interp.bind_set(*verts_var, verts);
  interp.bind_set(*tets_var, tets);
  auto first_start = Clock::now();
  std::vector<Value> r = interp.call(*stiffness, {});
  const double first_ms =
      std::chrono::duration<double, std::milli>(Clock::now() - first_start).count();
  const int builds_after_first = interp.patterns().builds();
  double checksum = 0.0;
  auto start = Clock::now();
  for (int n = 0; n < repeats; ++n) {
    r = interp.call(*stiffness, {});
    checksum += r[0].matrix()->values()[0];
  }
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count() /
                    std::max(repeats, 1);
  const simit::runtime::SystemMatrix& K = *r[0].matrix();
  std::printf("first assembly (builds the pattern): %.1f ms\n", first_ms);
  std::printf("assembly: %.1f ms per assembly over %d assemblies (%.2f us per tet)\n", ms, repeats,
              1e3 * ms / tets.size());
  std::printf("patterns built: %d after the first assembly, %d after all %d\n", builds_after_first,
              interp.patterns().builds(), repeats + 1);
  std::printf("matrix: %d x %d blocks of 3x3, %lld blocks\n", K.rows(), K.cols(),
              static_cast<long long>(K.pattern().nnz()));
  std::printf("matrix values: %zu bytes (%.1f MiB)\n", K.value_bytes(),
              K.value_bytes() / 1048576.0);
  std::printf(
      "pattern: %zu bytes CSR index (row pointers + column indices, %.1f MiB) + %zu bytes "
      "assembly index (%.1f MiB)\n",
      K.pattern().index_bytes(), K.pattern().index_bytes() / 1048576.0,
      K.pattern().assembly_bytes(), K.pattern().assembly_bytes() / 1048576.0);
  std::printf("values + one int per block + one int per row: %zu bytes\n",
              K.value_bytes() + sizeof(int32_t) * (K.pattern().nnz() + K.rows()));

  // One hooked run for the split.
  PhaseTimer timer(*element);
  simit::api::EngineOptions options;
  options.hook = &timer;
  simit::api::Engine hooked(c, options);
  hooked.bind_set(*verts_var, verts);
  hooked.bind_set(*tets_var, tets);
  hooked.call(*stiffness, {});  // pattern and warm-up
  timer.reset();
  auto hstart = Clock::now();
  std::vector<Value> hr = hooked.call(*stiffness, {});
  timer.stop();
  const double hooked_ms = std::chrono::duration<double, std::milli>(Clock::now() - hstart).count();
  // Hook cost: the hooked run is slower by a roughly constant cost per statement; it is
  // removed from each phase in proportion to its statement count.
  const long counts[] = {timer.count(PhaseTimer::Element), timer.count(PhaseTimer::Scatter),
                         timer.count(PhaseTimer::Boundary), timer.count(PhaseTimer::Driver)};
  const long statements = counts[0] + counts[1] + counts[2] + counts[3];
  // The hook's own body runs between two clock reads and is in no phase; what the phases hold
  // beyond the plain run's time is the rest of the hook's cost (call, clock latency).
  const double elem_raw = timer.seconds(PhaseTimer::Element);
  const double scat_raw = timer.seconds(PhaseTimer::Scatter) + timer.seconds(PhaseTimer::Boundary);
  const double driver_raw = timer.seconds(PhaseTimer::Driver);
  const double per_statement =
      std::max(0.0, (elem_raw + scat_raw + driver_raw - ms / 1e3) / statements);
  const double elem = elem_raw - per_statement * counts[0];
  const double scat = scat_raw - per_statement * (counts[1] + counts[2]);
  const double driver = driver_raw - per_statement * counts[3];
  const double raw_total = elem_raw + scat_raw + driver_raw, total = elem + scat + driver;
  std::printf(
      "hooked assembly: %.1f ms (a clock read before each of %ld statements; %.3f us hook "
      "cost per statement inside the phases: their sum minus the plain time)\n",
      hooked_ms, statements, 1e6 * per_statement);
  std::printf("  phase              raw (hooked)        hook cost removed\n");
  std::printf("  element functions: %8.1f ms %5.1f%%   %8.1f ms %5.1f%%  (%ld statements)\n",
              1e3 * elem_raw, 100.0 * elem_raw / raw_total, 1e3 * elem, 100.0 * elem / total,
              counts[0]);
  std::printf("  scatter:           %8.1f ms %5.1f%%   %8.1f ms %5.1f%%  (%ld block writes)\n",
              1e3 * scat_raw, 100.0 * scat_raw / raw_total, 1e3 * scat, 100.0 * scat / total,
              counts[1] + counts[2] + 1);
  std::printf(
      "  driver:            %8.1f ms %5.1f%%   %8.1f ms %5.1f%%  (pattern lookup, zeroing)\n",
      1e3 * driver_raw, 100.0 * driver_raw / raw_total, 1e3 * driver, 100.0 * driver / total);
  if (counts[1] && counts[2])
    std::printf(
        "  (scatter intervals ending at an element's first statement, which also hold the "
        "map's per-element overhead: %.3f us on average, other scatter statements %.3f us)\n",
        1e6 * timer.seconds(PhaseTimer::Boundary) / counts[2],
        1e6 * timer.seconds(PhaseTimer::Scatter) / counts[1]);
  std::printf("checksum %.6e\n", checksum + hr[0].matrix()->values()[0]);
  return 0;
}
