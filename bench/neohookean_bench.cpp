// Times the interpreter on a Neo-Hookean stress function for a 3x3 deformation gradient:
// N calls (default 100,000) of `neohookean_stress`, reported in microseconds per call.
// Usage: neohookean_bench [calls] [program.sim]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "api/engine.h"

namespace {

using simit::interp::Value;

Value gradient(double perturbation) {
  const double f[9] = {1.1, 0.1, 0.0, 0.0, 0.9, 0.2, 0.05, 0.0, 1.2};
  simit::runtime::Tensor t(simit::runtime::ComponentKind::Float, simit::runtime::Shape{3, 3});
  for (int i = 0; i < 9; ++i) t.mutable_floats()[i] = f[i] + (i == 0 ? perturbation : 0.0);
  return Value::of_tensor(std::move(t));
}

}  // namespace

int main(int argc, char** argv) {
  const long calls = argc > 1 ? std::atol(argv[1]) : 100000;
  const std::string path =
      argc > 2 ? argv[2] : SIMIT_SOURCE_DIR "/tests/interp/programs/neohookean.sim";
  auto c = simit::api::CompiledProgram::from_file(path);
  if (!c->ok()) {
    std::fputs(c->compilation()->diagnostics.render_all().c_str(), stderr);
    return 1;
  }
  const auto* f = c->find_func("neohookean_stress");
  if (!f) {
    std::fprintf(stderr, "no function neohookean_stress in %s\n", path.c_str());
    return 1;
  }
  simit::api::Engine interp(c);
  const Value mu = Value::of_float(3.5e5), lambda = Value::of_float(1.2e6);
  double checksum = 0.0;
  auto run = [&](long n) {
    for (long i = 0; i < n; ++i) {
      std::vector<Value> r =
          interp.call(*f, {gradient(1e-9 * static_cast<double>(i % 7)), mu, lambda});
      checksum += r[0].tensor().floats()[0];
    }
  };
  run(calls / 10 + 1);  // warm up
  auto start = std::chrono::steady_clock::now();
  run(calls);
  auto end = std::chrono::steady_clock::now();
  double us = std::chrono::duration<double, std::micro>(end - start).count();
  std::printf("neohookean_stress: %ld calls, %.3f us per call (checksum %.6e)\n", calls,
              us / static_cast<double>(calls), checksum);
  return 0;
}
