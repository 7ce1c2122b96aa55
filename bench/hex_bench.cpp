// Times the assembly of a hexahedral mesh's stiffness matrix (bench/programs/hex_stiffness.sim:
// a 24 x 24 element matrix per hex, whose B' (C B) product the JIT tiles) under the
// interpreter and under the JIT, side by side in one process, and checks that both give the
// same matrix bit for bit.
//
// Usage: hex_bench [N] [REPEAT]   (an N x N x N grid of unit hexes, slightly sheared;
//                                  default 8 and 5; the median of REPEAT assemblies each)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "api/engine.h"
#include "runtime/set.h"

namespace {

using simit::api::CompiledProgram;
using simit::api::Engine;
using simit::api::EngineOptions;
using simit::api::ExecutorKind;
using simit::interp::Value;
using Clock = std::chrono::steady_clock;

struct Grid {
  simit::runtime::Set verts{"verts"};
  simit::runtime::Set hexes{"hexes",
                            {&verts, &verts, &verts, &verts, &verts, &verts, &verts, &verts}};

  explicit Grid(int n) {
    const int m = n + 1;
    verts.add_many(m * m * m);
    verts.add_field("x",
                    simit::runtime::FieldType{simit::runtime::ComponentKind::Float, {3}, false});
    auto id = [&](int i, int j, int k) { return (k * m + j) * m + i; };
    for (int k = 0; k < m; ++k)
      for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i) {
          double* x = verts.field(0).at<double>(id(i, j, k));
          x[0] = i + 0.1 * j;  // sheared, so that no two elements are alike
          x[1] = j + 0.05 * k * k / m;
          x[2] = k;
        }
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
          hexes.add({id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
                     id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1),
                     id(i, j + 1, k + 1)});
  }
};

struct Timing {
  double median_ms = 0.0, first_ms = 0.0;
  Value k;
  std::string stats;
};

Timing time_assembly(const std::shared_ptr<const CompiledProgram>& program, ExecutorKind kind,
                     int n, int repeat) {
  Grid grid(n);
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  // SIMIT_HEX_DUMP=1: the compiled trace's loop IR to stderr.
  std::ostringstream dump;
  if (const char* d = std::getenv("SIMIT_HEX_DUMP"); d && *d == '1') {
    o.dump = &dump;
    o.executor.dump_loop_ir = true;
  }
  Engine engine(program, o);
  engine.bind_set(*program->find_extern("verts"), grid.verts);
  engine.bind_set(*program->find_extern("hexes"), grid.hexes);
  const auto& assemble = *program->find_func("assemble");
  Timing t;
  std::vector<double> ms;
  for (int r = 0; r <= repeat; ++r) {
    const auto start = Clock::now();
    t.k = engine.call(assemble, {})[0];
    const double d = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (r == 0)
      t.first_ms = d;  // the JIT compiles here
    else
      ms.push_back(d);
  }
  std::sort(ms.begin(), ms.end());
  t.median_ms = ms[ms.size() / 2];
  std::ostringstream os;
  engine.print_jit_stats(os);
  t.stats = os.str();
  std::fprintf(stderr, "%s", dump.str().c_str());
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 8;
  const int repeat = argc > 2 ? std::atoi(argv[2]) : 5;
  if (n < 1 || repeat < 1) {
    std::fprintf(stderr, "usage: hex_bench [N >= 1] [REPEAT >= 1]\n");
    return 2;
  }
  const std::string path = std::string(SIMIT_SOURCE_DIR) + "/bench/programs/hex_stiffness.sim";
  auto program = CompiledProgram::from_file(path);
  if (!program->ok()) {
    std::fprintf(stderr, "%s", program->compilation()->diagnostics.render_all().c_str());
    return 1;
  }
  const Timing in = time_assembly(program, ExecutorKind::Interpreter, n, repeat);
  if (!simit::api::jit_available()) {
    std::printf("%d hexes: interpreter %.2f ms per assembly; this build has no JIT\n", n * n * n,
                in.median_ms);
    return 0;
  }
  const Timing jit = time_assembly(program, ExecutorKind::Jit, n, repeat);
  const auto &a = *in.k.matrix(), &b = *jit.k.matrix();
  size_t differ = 0;
  for (int64_t i = 0; i < a.scalar_rows(); ++i)
    for (int64_t j = 0; j < a.scalar_cols(); ++j) {
      const double u = a.component(i, j), v = b.component(i, j);
      differ += std::memcmp(&u, &v, sizeof u) != 0 && !(u == 0.0 && v == 0.0);
    }
  std::printf("%d hexes (24 x 24 element matrices), median of %d assemblies:\n", n * n * n, repeat);
  std::printf(
      "  interpreter %9.2f ms\n  jit         %9.2f ms  (%.1fx; first call with the compile "
      "%.1f ms)\n  components that differ: %zu of %lld\n",
      in.median_ms, jit.median_ms, in.median_ms / jit.median_ms, jit.first_ms, differ,
      static_cast<long long>(a.scalar_rows() * a.scalar_cols()));
  std::printf("%s", jit.stats.c_str());
  return differ == 0 ? 0 : 1;
}
