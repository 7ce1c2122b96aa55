// The CPU code generator: loop IR to LLVM IR (jit/cpu/emitter.h), optimised for the host and
// linked through one ORC session, one resource tracker per kernel (dropping a kernel frees
// its code).
#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>

#include <llvm/ExecutionEngine/Orc/CompileUtils.h>
#include <llvm/ExecutionEngine/Orc/ExecutionUtils.h>
#include <llvm/ExecutionEngine/Orc/JITTargetMachineBuilder.h>
#include <llvm/ExecutionEngine/Orc/LLJIT.h>
#include <llvm/IR/Verifier.h>
#include <llvm/Passes/PassBuilder.h>
#include <llvm/Support/TargetSelect.h>
#include <llvm/Support/raw_ostream.h>
#include <llvm/Target/TargetMachine.h>

#include "jit/cpu/emitter.h"

namespace simit::jit {

namespace {

using cpu::Emitter;
using cpu::lanes_fit;

std::string message_of(llvm::Error e) { return llvm::toString(std::move(e)); }

// A module flag: compile with LLVM's fast instruction selector and register allocator.
constexpr const char* kFastCodegen = "simit.fast-codegen";

// Object code for each module from a target machine of its own (so compiles on several
// threads stay apart), at the host's best code generation unless the module asks for the fast
// one (jit/tunables.h, kLargeTraceFastCodegen).
class Compiler : public llvm::orc::IRCompileLayer::IRCompiler {
 public:
  explicit Compiler(llvm::orc::JITTargetMachineBuilder jtmb, const llvm::TargetOptions& options)
      : IRCompiler(llvm::orc::irManglingOptionsFromTargetOptions(options)),
        jtmb_(std::move(jtmb)) {}

  llvm::Expected<std::unique_ptr<llvm::MemoryBuffer>> operator()(llvm::Module& m) override {
    llvm::orc::JITTargetMachineBuilder jtmb = jtmb_;
    if (m.getModuleFlag(kFastCodegen)) jtmb.setCodeGenOptLevel(llvm::CodeGenOptLevel::None);
    auto tm = jtmb.createTargetMachine();
    if (!tm) return tm.takeError();
    return llvm::orc::SimpleCompiler(**tm)(m);
  }

 private:
  llvm::orc::JITTargetMachineBuilder jtmb_;
};

// The one ORC session of the process: its code lives as long as the kernels that own it.
class Session {
 public:
  static Session* get(std::string& error) {
    static std::once_flag once;
    static std::unique_ptr<Session> session;
    static std::string failure;
    std::call_once(once, [] {
      llvm::InitializeNativeTarget();
      llvm::InitializeNativeTargetAsmPrinter();
      auto s = std::unique_ptr<Session>(new Session());
      failure = s->start();
      if (failure.empty()) session = std::move(s);
    });
    error = failure;
    return session.get();
  }

  llvm::orc::LLJIT& jit() { return *jit_; }
  llvm::TargetMachine& target() { return *tm_; }

 private:
  std::string start() {
    auto jtmb = llvm::orc::JITTargetMachineBuilder::detectHost();
    if (!jtmb) return message_of(jtmb.takeError());
    // The arithmetic contract: no fused multiply-add, whatever the host offers.
    jtmb->getOptions().AllowFPOpFusion = llvm::FPOpFusion::Strict;
    jtmb->getFeatures().AddFeature("fma", false);
    jtmb->getFeatures().AddFeature("avx512f", false);
    jtmb->setCodeGenOptLevel(llvm::CodeGenOptLevel::Aggressive);
    auto tm = jtmb->createTargetMachine();
    if (!tm) return message_of(tm.takeError());
    tm_ = std::move(*tm);
    auto jit =
        llvm::orc::LLJITBuilder()
            .setJITTargetMachineBuilder(*jtmb)
            .setCompileFunctionCreator(
                [options = tm_->Options](llvm::orc::JITTargetMachineBuilder b)
                    -> llvm::Expected<std::unique_ptr<llvm::orc::IRCompileLayer::IRCompiler>> {
                  return std::make_unique<Compiler>(std::move(b), options);
                })
            .create();
    if (!jit) return message_of(jit.takeError());
    jit_ = std::move(*jit);
    auto gen = llvm::orc::DynamicLibrarySearchGenerator::GetForCurrentProcess(
        jit_->getDataLayout().getGlobalPrefix());
    if (!gen) return message_of(gen.takeError());
    jit_->getMainJITDylib().addGenerator(std::move(*gen));
    return "";
  }

  std::unique_ptr<llvm::orc::LLJIT> jit_;
  std::unique_ptr<llvm::TargetMachine> tm_;
};

// The compiled function's signatures (jit/target.h describes the arguments).
using MapFn = int32_t (*)(void* const* arrays, const double* scalars, const int32_t* endpoints,
                          int32_t begin, int32_t end, int32_t* failed_element);
using SystemFn = int32_t (*)(void* const* arrays, double* scalars, const int64_t* sizes,
                             const void* interrupt);

class CpuKernel : public Kernel {
 public:
  explicit CpuKernel(llvm::orc::ResourceTrackerSP rt) : rt_(std::move(rt)) {}
  void* address = nullptr;
  bool system = false;
  ~CpuKernel() override {
    if (rt_) llvm::consumeError(rt_->remove());
  }
  int32_t run(const MapArgs& a, ElementRange r, int32_t* failed) const override {
    return system ? 0
                  : reinterpret_cast<MapFn>(address)(a.arrays, a.scalars, a.endpoints, r.begin,
                                                     r.end, failed);
  }
  int32_t run(const SystemArgs& a) const override {
    return system ? reinterpret_cast<SystemFn>(address)(a.arrays, a.scalars, a.sizes, a.interrupt)
                  : 0;
  }

 private:
  llvm::orc::ResourceTrackerSP rt_;
};

void optimise(llvm::Module& m, llvm::TargetMachine& tm, int level_number) {
  llvm::LoopAnalysisManager lam;
  llvm::FunctionAnalysisManager fam;
  llvm::CGSCCAnalysisManager cgam;
  llvm::ModuleAnalysisManager mam;
  // As clang at -O2: the loop and SLP vectorizers on (lane-wise IEEE operations, no
  // reassociation: the bits do not change).
  llvm::PipelineTuningOptions tuning;
  tuning.LoopVectorization = level_number >= 2;
  tuning.SLPVectorization = level_number >= 2;
  llvm::PassBuilder pb(&tm, tuning);
  pb.registerModuleAnalyses(mam);
  pb.registerCGSCCAnalyses(cgam);
  pb.registerFunctionAnalyses(fam);
  pb.registerLoopAnalyses(lam);
  pb.crossRegisterProxies(lam, fam, cgam, mam);
  const llvm::OptimizationLevel level = level_number >= 3   ? llvm::OptimizationLevel::O3
                                        : level_number == 2 ? llvm::OptimizationLevel::O2
                                                            : llvm::OptimizationLevel::O1;
  llvm::ModulePassManager mpm = pb.buildPerModuleDefaultPipeline(level);
  mpm.run(m, mam);
}

class CpuTarget : public Target {
 public:
  CpuTarget(Session& s, const HostCalls& host) : s_(s), host_(host) {}
  const char* name() const override { return "cpu"; }

  std::unique_ptr<Kernel> compile(const Trace& trace, bool keep_ir, std::string& error) override {
    const bool large = node_count(trace) > kLargeTrace, lanes = lanes_fit(trace);
    const int level = !large ? kOptLevel : lanes ? kLargeLanesTraceOptLevel : kLargeTraceOptLevel;
    const bool fast = large && !lanes && kLargeTraceFastCodegen;
    auto k = build(level, keep_ir, error, [&](llvm::Module& m, const std::string& name) {
      if (fast) m.addModuleFlag(llvm::Module::Warning, kFastCodegen, 1);
      return Emitter(trace, m, host_).run(name);
    });
    if (k) k->lanes = lanes ? kLanes : 1;
    return k;
  }
  std::unique_ptr<Kernel> compile(const SystemTrace& trace, bool keep_ir,
                                  std::string& error) override {
    auto k = build(kOptLevel, keep_ir, error, [&](llvm::Module& m, const std::string& name) {
      return Emitter(trace, m).run_system(name);
    });
    if (k) k->system = true;
    return k;
  }

 private:
  // Emits a function into a new module, optimises it for the host and links it.
  std::unique_ptr<CpuKernel> build(
      int level, bool keep_ir, std::string& error,
      const std::function<llvm::Function*(llvm::Module&, const std::string&)>& emit) {
    const auto start = std::chrono::steady_clock::now();
    static std::atomic<int> serial{0};
    const std::string name = "simit_kernel_" + std::to_string(serial++);
    auto ctx = std::make_unique<llvm::LLVMContext>();
    auto mod = std::make_unique<llvm::Module>(name, *ctx);
    mod->setDataLayout(s_.jit().getDataLayout());
    mod->setTargetTriple(s_.target().getTargetTriple().str());
    llvm::Function* fn = emit(*mod, name);
    fn->addFnAttr("target-cpu", s_.target().getTargetCPU());
    fn->addFnAttr("target-features", s_.target().getTargetFeatureString());
    std::string broken;
    llvm::raw_string_ostream bs(broken);
    if (llvm::verifyModule(*mod, &bs)) {
      error = "LLVM rejected the generated code: " + bs.str();
      return nullptr;
    }
    if (level > 0) optimise(*mod, s_.target(), level);
    std::string ir;
    if (keep_ir) {
      llvm::raw_string_ostream os(ir);
      mod->print(os, nullptr);
    }
    auto rt = s_.jit().getMainJITDylib().createResourceTracker();
    if (llvm::Error e =
            s_.jit().addIRModule(rt, llvm::orc::ThreadSafeModule(std::move(mod), std::move(ctx)))) {
      error = message_of(std::move(e));
      return nullptr;
    }
    auto sym = s_.jit().lookup(name);
    if (!sym) {
      error = message_of(sym.takeError());
      llvm::consumeError(rt->remove());
      return nullptr;
    }
    auto k = std::make_unique<CpuKernel>(rt);
    k->address = sym->toPtr<void*>();
    k->llvm_ir = std::move(ir);
    k->compile_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return k;
  }

 private:
  Session& s_;
  HostCalls host_;
};

}  // namespace

std::unique_ptr<Target> make_cpu_target(const HostCalls& host, const std::string& cache_dir,
                                        std::string& error) {
  (void)cache_dir;
  Session* s = Session::get(error);
  if (!s) return nullptr;
  return std::make_unique<CpuTarget>(*s, host);
}

}  // namespace simit::jit
