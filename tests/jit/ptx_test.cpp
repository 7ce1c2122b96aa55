// The GPU target: traces compiled to PTX through LLVM's NVPTX back end (an `.entry` per map
// kernel, every multiplication and addition its own correctly rounded instruction, no fma),
// what it refuses and why, and the PTX assembled by the CUDA toolkit's ptxas where it is
// installed (no GPU is needed). Programs run through the engine with --check-ptx and
// --dump=ptx.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <bit>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "api/engine.h"
#include "interp/runtime_error.h"
#include "jit/ptx/device_math.h"
#include "jit/ptx/ptx_check.h"
#include "jit/ptx/ptx_target.h"
#include "runtime/math/math_functions.h"

namespace simit::jit {
namespace {

using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;

ExprRef node(ExprKind kind, Ty ty, uint8_t op, std::vector<ExprRef> ops, int slot = 0) {
  Expr e;
  e.kind = kind;
  e.ty = ty;
  e.op = op;
  e.slot = slot;
  e.ops = std::move(ops);
  return std::make_shared<const Expr>(std::move(e));
}
ExprRef element() { return node(ExprKind::Element, Ty::I32, 0, {}); }
ExprRef load(int slot) { return node(ExprKind::Load, Ty::F64, 0, {element()}, slot); }
ExprRef scalar(int slot) { return node(ExprKind::Scalar, Ty::F64, 0, {}, slot); }
ExprRef binary(BinOp op, ExprRef a, ExprRef b) {
  return node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(op), {std::move(a), std::move(b)});
}
ExprRef constant(double v) {
  Expr e;
  e.f = v;
  return std::make_shared<const Expr>(std::move(e));
}

ArraySlot field(const std::string& name) {
  ArraySlot a;
  a.kind = ArraySlot::Kind::Field;
  a.name = name;
  return a;
}

// r(e) += a(e) * b(e) + c over a set's elements: the multiply-add a contracting compiler
// would fuse.
Trace multiply_add() {
  Trace t;
  t.name = "multiply_add";
  t.reduce = true;
  ArraySlot r;
  r.kind = ArraySlot::Kind::Result;
  r.written = true;
  r.name = "r";
  t.arrays = {field("a"), field("b"), r};
  t.scalars = {Ty::F64};
  Stmt s;
  s.kind = StmtKind::Assemble;
  s.slot = 2;
  s.index = element();
  s.value = binary(BinOp::Add, binary(BinOp::Mul, load(0), load(1)), scalar(0));
  t.body.push_back(std::move(s));
  return t;
}

// The same, with sin(a) added, a quotient and a square root, and a check that a > 0.
Trace with_math_and_check() {
  Trace t = multiply_add();
  t.name = "with_math_and_check";
  Stmt check;
  check.kind = StmtKind::Check;
  check.error = 0;
  check.value =
      node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(CmpOp::Gt), {load(0), constant(0.0)});
  t.errors.push_back(ErrorSite{{}, "a must be positive"});
  ExprRef sine = node(ExprKind::Math, Ty::F64, static_cast<uint8_t>(MathFn::Sin), {load(0)});
  ExprRef root = node(ExprKind::Math, Ty::F64, static_cast<uint8_t>(MathFn::Sqrt), {load(1)});
  Stmt& add = t.body[0];
  add.value = binary(BinOp::Add, add.value, binary(BinOp::Div, sine, root));
  t.body.insert(t.body.begin(), std::move(check));
  return t;
}

// r(e) += exp(a) + log(b) + atan2(a, b): three of the project's math functions.
Trace with_exp_log_atan2() {
  Trace t = multiply_add();
  t.name = "with_exp_log_atan2";
  auto math = [](MathFn f, std::vector<ExprRef> args) {
    return node(ExprKind::Math, Ty::F64, static_cast<uint8_t>(f), std::move(args));
  };
  t.body[0].value = binary(
      BinOp::Add, binary(BinOp::Add, math(MathFn::Exp, {load(0)}), math(MathFn::Log, {load(1)})),
      math(MathFn::Atan2, {load(0), load(1)}));
  return t;
}

std::unique_ptr<Target> gpu() {
  std::string error;
  auto t = ptx::make_ptx_target(ptx::kDefaultGpuArch, error);
  EXPECT_TRUE(t) << error;
  return t;
}

std::string ptx_of(const Trace& trace) {
  auto target = gpu();
  if (!target) return "";
  std::string error;
  std::unique_ptr<Kernel> k = target->compile(trace, false, error);
  const auto* p = dynamic_cast<const ptx::PtxKernel*>(k.get());
  EXPECT_TRUE(p) << error;
  return p ? p->ptx : "";
}

bool has(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

// ptxas's path, or "" (the test that needs it skips, saying why).
std::string ptxas() {
  std::string why;
  return ptx::find_ptxas(why);
}

TEST(Ptx, AMapKernelIsAnEntryWithCorrectlyRoundedMultiplicationsAndAdditions) {
  const std::string p = ptx_of(multiply_add());
  EXPECT_TRUE(has(p, ".version ")) << p;
  EXPECT_TRUE(has(p, ".target sm_90")) << p;
  EXPECT_TRUE(has(p, ".entry simit_map(")) << p;
  EXPECT_TRUE(has(p, "mul.rn.f64")) << p;
  EXPECT_TRUE(has(p, "add.rn.f64")) << p;
  EXPECT_FALSE(has(p, "fma")) << p;
  // One element per thread: the block and thread indices; the assembly's addition is a plain
  // load and store (no atomic add).
  EXPECT_TRUE(has(p, "%ctaid.x")) << p;
  EXPECT_TRUE(has(p, "%ntid.x")) << p;
  EXPECT_TRUE(has(p, "%tid.x")) << p;
  EXPECT_FALSE(has(p, "atom")) << p;
}

TEST(Ptx, MathFunctionsAreLinkedInAndAFailureKeepsTheLowestElement) {
  const std::string p = ptx_of(with_math_and_check());
  // With the device bitcode, sin is part of the module; without it, an external call.
  if (ptx::device_math_available())
    EXPECT_FALSE(has(p, ".extern .func")) << p;
  else
    EXPECT_TRUE(has(p, ".extern .func  (.param .b64 func_retval0) simit_math_sin")) << p;
  EXPECT_TRUE(has(p, "div.rn.f64")) << p;
  EXPECT_TRUE(has(p, "sqrt.rn.f64")) << p;
  EXPECT_TRUE(has(p, "atom.global.min.u64")) << p;  // the failure word, an integer minimum
  EXPECT_FALSE(has(p, "fma")) << p;
  // The failure word's encoding.
  const uint64_t word = (uint64_t{41} << 32) | 3u;
  EXPECT_EQ(ptx::failed_element(word), 41);
  EXPECT_EQ(ptx::failed_check(word), 3);
  EXPECT_LT(word, ptx::kNoFailure);
}

// The device bitcode (the project's math sources compiled for nvptx) linked into the module:
// exp, log and atan2 are defined in it (inlined into the kernel, or `.func`s of its own: the
// accurate paths the sources keep out of line), never external, and still without an fma, so
// ptxas assembles the module as a whole program (no -c).
TEST(Ptx, TheMathFunctionsDeviceBitcodeMakesAWholeModule) {
  if (!ptx::device_math_available())
    GTEST_SKIP() << "this build has no device math bitcode (clang++ or llvm-link not found)";
  const std::string p = ptx_of(with_exp_log_atan2());
  EXPECT_TRUE(has(p, ".entry simit_map(")) << p;
  EXPECT_FALSE(has(p, ".extern")) << p;
  EXPECT_FALSE(has(p, "simit_math_")) << p;  // no call left by name
  EXPECT_TRUE(has(p, ".func ")) << p;        // atan2's accurate path, out of line
  EXPECT_TRUE(has(p, "atan2_accurate")) << p;
  EXPECT_TRUE(has(p, ".global .align 8 .b8 ")) << p;  // the tables, in the module
  EXPECT_FALSE(has(p, "fma")) << p;
  EXPECT_TRUE(has(p, "mul.rn.f64")) << p;
  const std::string path = ptxas();
  if (path.empty()) GTEST_SKIP() << "ptxas not found ($SIMIT_PTXAS, PATH, /usr/local/cuda/bin)";
  std::string message;
  EXPECT_TRUE(ptx::assemble(path, p, ptx::kDefaultGpuArch, message)) << message;
}

// ptxas's arguments: a whole module is assembled as a program, one that calls an external
// function as relocatable code (-c), which ptxas without -c would refuse to link. An
// "assembler" that writes its arguments down shows which.
TEST(Ptx, OnlyAModuleWithExternalFunctionsIsAssembledAsRelocatableCode) {
  char dir[] = "/tmp/simit_ptx_test_XXXXXX";
  ASSERT_TRUE(::mkdtemp(dir));
  const std::string script = std::string(dir) + "/ptxas", log = std::string(dir) + "/args";
  {
    std::ofstream f(script);
    f << "#!/bin/sh\necho \"$@\" > " << log << "\n";
  }
  ASSERT_EQ(::chmod(script.c_str(), 0755), 0);
  auto args_for = [&](const std::string& ptx) {
    std::string message;
    EXPECT_TRUE(ptx::assemble(script, ptx, "sm_90", message)) << message;
    std::ifstream in(log);
    std::string line;
    std::getline(in, line);
    return line;
  };
  const std::string whole = ".version 8.5\n.target sm_90\n.address_size 64\n";
  const std::string calls = whole + ".extern .func  (.param .b64 func_retval0) simit_math_exp\n";
  const std::string a = args_for(whole), b = args_for(calls);
  EXPECT_TRUE(has(a, "--gpu-name sm_90 ")) << a;
  EXPECT_FALSE(has(a, " -c ")) << a;
  EXPECT_TRUE(has(b, "--gpu-name sm_90 -c ")) << b;
  std::filesystem::remove_all(dir);
}

// Inputs for the math functions: the special values, bit patterns drawn at random (every
// exponent, subnormals, infinities, NaNs) and values drawn at random in [-20, 20] and [-1, 1].
std::vector<double> math_inputs() {
  std::vector<double> xs = {
      0.0,     -0.0,   1.0,   -1.0,     0.5,       -0.5,  2.0,     1e-310,
      -1e-310, 1e-300, 1e300, -1e300,   1e22,      -1e22, 3.14159, 1.5707963267948966,
      710.0,   -745.5, 1e-8,  INFINITY, -INFINITY, NAN};
  uint64_t state = 0x243f6a8885a308d3u;
  auto next = [&] { return state = state * 6364136223846793005u + 1442695040888963407u; };
  for (int i = 0; i < 4000; ++i) xs.push_back(std::bit_cast<double>(next()));
  for (int i = 0; i < 4000; ++i) xs.push_back(40.0 * ((next() >> 11) * 0x1p-53) - 20.0);
  for (int i = 0; i < 4000; ++i) xs.push_back(2.0 * ((next() >> 11) * 0x1p-53) - 1.0);
  return xs;
}

// The same bits, any NaN being as good as another.
bool same(double a, double b) {
  return std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b) ||
         (std::isnan(a) && std::isnan(b));
}

// The device bitcode compiled for this CPU computes the host's functions' bits: the device
// compile (clang for nvptx, the std shim for the host's headers, no contraction) changes
// nothing in the arithmetic. (On the GPU the same IR is lowered to the correctly rounded
// add.rn/mul.rn/div.rn/sqrt.rn.f64.)
TEST(Ptx, TheDeviceMathBitcodeComputesTheHostsBits) {
  if (!ptx::device_math_available())
    GTEST_SKIP() << "this build has no device math bitcode (clang++ or llvm-link not found)";
  using Unary = double (*)(double);
  using Binary = double (*)(double, double);
  const std::pair<const char*, Unary> unary[] = {
      {"exp", math::exp}, {"log", math::log},   {"sin", math::sin},   {"cos", math::cos},
      {"tan", math::tan}, {"asin", math::asin}, {"acos", math::acos}, {"cbrt", math::cbrt}};
  const std::pair<const char*, Binary> binary[] = {{"pow", math::pow}, {"atan2", math::atan2}};
  const std::vector<double> xs = math_inputs();
  std::string error;
  for (const auto& [name, host] : unary) {
    auto device =
        reinterpret_cast<Unary>(ptx::device_math_on_host(std::string("simit_math_") + name, error));
    ASSERT_TRUE(device) << error;
    int wrong = 0;
    for (double x : xs)
      if (!same(device(x), host(x)) && ++wrong <= 3)
        ADD_FAILURE() << name << "(" << x << "): " << device(x) << " on the device's code, "
                      << host(x) << " on the host's";
    EXPECT_EQ(wrong, 0) << name;
  }
  for (const auto& [name, host] : binary) {
    auto device = reinterpret_cast<Binary>(
        ptx::device_math_on_host(std::string("simit_math_") + name, error));
    ASSERT_TRUE(device) << error;
    int wrong = 0;
    for (size_t i = 0; i + 1 < xs.size(); ++i) {
      const double x = xs[i], y = xs[xs.size() - 1 - i];
      if (!same(device(x, y), host(x, y)) && ++wrong <= 3)
        ADD_FAILURE() << name << "(" << x << ", " << y << "): " << device(x, y)
                      << " on the device's code, " << host(x, y) << " on the host's";
    }
    EXPECT_EQ(wrong, 0) << name;
  }
  EXPECT_FALSE(ptx::device_math_on_host("simit_math_none", error));
  EXPECT_TRUE(has(error, "has no simit_math_none")) << error;
}

TEST(Ptx, TracesThatCallTheRuntimeAndSystemTracesNotForTheDeviceAreRefusedWithTheirReason) {
  Trace t = multiply_add();
  Stmt d;
  d.kind = StmtKind::Decompose;
  d.fn = static_cast<int>(Decomposition::Svd);
  d.n = 1;
  d.args = {load(0)};
  d.error = 0;
  t.errors.push_back(ErrorSite{{}, "svd failed"});
  t.locals = {Ty::F64, Ty::F64, Ty::F64};
  d.outs = {0, 1, 2};
  Stmt branch;
  branch.kind = StmtKind::If;
  branch.value =
      node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(CmpOp::Gt), {load(0), constant(0.0)});
  branch.body.push_back(std::move(d));  // nested: the refusal looks inside branches
  t.body.push_back(std::move(branch));
  const std::string why =
      "calls the runtime's simit_jit_decompose, which has no device version yet";
  EXPECT_EQ(ptx::gpu_refusal(t), why);
  auto target = gpu();
  ASSERT_TRUE(target);
  std::string error;
  EXPECT_FALSE(target->compile(t, false, error));
  EXPECT_EQ(error, why);
  // A system trace runs on the GPU only as a device program, and one whose pass checks a
  // value (its units could not run apart) not at all.
  SystemTrace s;
  EXPECT_FALSE(target->compile(s, false, error));
  EXPECT_EQ(error, "not lowered as a device program");
  EXPECT_EQ(error, ptx::gpu_refusal(s));
  s.device = true;
  s.sizes = {"n"};
  s.locals = {Ty::F64};
  VectorOp pass;
  pass.kind = VectorOp::Kind::Pass;
  pass.length = 0;
  Stmt check;
  check.kind = StmtKind::Check;
  check.value = node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(CmpOp::Gt),
                     {constant(1.0), constant(0.0)});
  check.error = 0;
  s.errors.push_back(ErrorSite{{}, "never"});
  pass.body.push_back(check);
  s.before.push_back(pass);
  EXPECT_FALSE(target->compile(s, false, error));
  EXPECT_EQ(error, "a pass or product checks a value");
}

TEST(Ptx, AnUnknownArchitectureIsAClearError) {
  std::string error;
  EXPECT_FALSE(ptx::make_ptx_target("sm_9000", error));
  EXPECT_EQ(error,
            "unknown GPU architecture 'sm_9000' (LLVM's NVPTX back end knows sm_XX, e.g. sm_90)");
  EXPECT_TRUE(ptx::make_ptx_target("sm_80", error)) << error;
}

TEST(Ptx, PtxasAssemblesTheKernelsAndRejectsBrokenPtx) {
  const std::string path = ptxas();
  if (path.empty()) GTEST_SKIP() << "ptxas not found ($SIMIT_PTXAS, PATH, /usr/local/cuda/bin)";
  std::string message;
  for (const Trace& t : {multiply_add(), with_math_and_check()})
    EXPECT_TRUE(ptx::assemble(path, ptx_of(t), ptx::kDefaultGpuArch, message))
        << t.name << ": " << message;
  std::string broken = ptx_of(multiply_add());
  broken.replace(broken.find("mul.rn.f64"), 10, "mul.xx.f64");
  EXPECT_FALSE(ptx::assemble(path, broken, ptx::kDefaultGpuArch, message));
  EXPECT_TRUE(has(message, "mul.xx.f64") || has(message, "error")) << message;
}

TEST(Ptx, AMissingPtxasIsNamedWhereItWasLookedFor) {
  const char* old = std::getenv("SIMIT_PTXAS");
  const std::string saved = old ? old : "";
  setenv("SIMIT_PTXAS", "/nonexistent/ptxas", 1);
  std::string why;
  EXPECT_EQ(ptx::find_ptxas(why), "");
  EXPECT_EQ(why, "SIMIT_PTXAS=/nonexistent/ptxas is not an executable file");
  ExecutorChoice choice;
  choice.check_ptx = true;
  EXPECT_EQ(executor_unavailable(choice), why);
  if (old)
    setenv("SIMIT_PTXAS", saved.c_str(), 1);
  else
    unsetenv("SIMIT_PTXAS");
}

// A map with a math function, a map that calls a decomposition and a vector update, run
// through the engine with --check-ptx and --dump=ptx.
const char* kProgram = R"(
element Vertex
  x : float;
  y : vector[3](float);
end
element Spring
  k : float;
end
extern verts : set{Vertex};
extern springs : set{Spring}(verts, verts);

func force(s : Spring, v : (Vertex * 2)) -> f : vector[verts](float)
  d = v(1).x - v(0).x;
  f(v(0)) = s.k * d + exp(d);
  f(v(1)) = -s.k * d;
end

func singular(s : Spring, v : (Vertex * 2)) -> g : vector[verts](vector[3](float))
  U, w, V = svd(v(0).y * v(1).y');
  g(v(0)) = w;
end

export func step() -> (f : vector[verts](float), g : vector[verts](vector[3](float)))
  f = map force to springs reduce +;
  g = map singular to springs reduce +;
  verts.x = verts.x + 0.5 * f;
end
)";

// The program's sets: four vertices on a chain of three springs.
struct Springs {
  runtime::Set verts{"verts"};
  runtime::Set springs{"springs", {&verts, &verts}};
  Springs() {
    verts.add_many(4);
    verts.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    verts.add_field("y", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
    for (int i = 0; i < 4; ++i) {
      verts.field(0).at<double>(i)[0] = 0.25 * i * i;
      for (int c = 0; c < 3; ++c) verts.field(1).at<double>(i)[c] = 1.0 + i - 0.5 * c;
    }
    const int32_t ends[] = {0, 1, 1, 2, 2, 3};
    springs.add_edges(ends);
    springs.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  }
};

// Runs step() under the JIT with --check-ptx (when `check`) and --dump=ptx into `dump`.
void run_step(bool check, std::ostream& dump) {
  auto compiled = CompiledProgram::from_source("ptx.sim", kProgram);
  ASSERT_TRUE(compiled->ok());
  Springs sets;
  EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  o.executor.check_ptx = check;
  o.executor.dump_ptx = true;
  o.dump = &dump;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("verts"), sets.verts);
  engine.bind_set(*compiled->find_extern("springs"), sets.springs);
  engine.call(*compiled->find_func("step"), {});
}

TEST(Ptx, ARunChecksEveryCompiledTraceAndDumpsItsPtx) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const bool assemble = !ptxas().empty();
  ptx::reset_tally();
  std::ostringstream dump;
  run_step(assemble, dump);
  const std::string d = dump.str();
  EXPECT_TRUE(has(d, "// PTX of force (line 24)\n")) << d;
  EXPECT_TRUE(has(d, ".entry simit_map(")) << d;
  // exp: linked in from the device bitcode, or called by name where the build has none.
  EXPECT_EQ(has(d, "simit_math_exp"), !ptx::device_math_available()) << d;
  EXPECT_FALSE(has(d, "fma")) << d;
  EXPECT_TRUE(has(d,
                  "// singular (line 25): not compiled for the GPU: calls the runtime's "
                  "simit_jit_decompose, which has no device version yet\n"))
      << d;
  // The system statement: a device program, a kernel per step.
  EXPECT_TRUE(has(d, "// PTX of statement (line 26)\n")) << d;
  EXPECT_TRUE(has(d, ".entry simit_step_step0(")) << d;
  if (!assemble) GTEST_SKIP() << "ptxas not found: the PTX was dumped, not assembled";
  EXPECT_EQ(check_ptx_summary(),
            "check-ptx: 2 traces assembled by ptxas, 1 not compiled for the GPU (1: calls the "
            "runtime's simit_jit_decompose, which has no device version yet)");
}

// An assembler that rejects everything (false(1)): the run stops at the first trace, naming
// it, and the tally counts the rejection.
TEST(Ptx, TheFirstPtxTheAssemblerRejectsStopsTheRun) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const char* old = std::getenv("SIMIT_PTXAS");
  const std::string saved = old ? old : "";
  setenv("SIMIT_PTXAS", "/bin/false", 1);
  ptx::reset_tally();
  std::ostringstream dump;
  try {
    run_step(true, dump);
    ADD_FAILURE() << "the run did not stop";
  } catch (const interp::RuntimeError& e) {
    EXPECT_EQ(e.message(),
              "--check-ptx: ptxas rejected the PTX of force (line 24): ptxas exited with status 1");
  }
  EXPECT_EQ(check_ptx_summary(),
            "check-ptx: 0 traces assembled by ptxas, 0 not compiled for the GPU, 1 rejected by "
            "ptxas");
  if (old)
    setenv("SIMIT_PTXAS", saved.c_str(), 1);
  else
    unsetenv("SIMIT_PTXAS");
}

}  // namespace
}  // namespace simit::jit
