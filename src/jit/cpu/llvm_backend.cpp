// The CPU code generator: loop IR to LLVM IR (jit/cpu/emitter.h), optimised for the host,
// compiled to object code and linked through one ORC session, one JITDylib per kernel
// (dropping a kernel frees its code). With a cache folder the object code is kept there,
// keyed by the trace and what it was compiled for, and a later run links it without
// compiling (jit/kernel_cache.h; docs/jit.md, "Kernel cache").
#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>

#include <llvm/Config/llvm-config.h>
#include <llvm/ExecutionEngine/Orc/CompileUtils.h>
#include <llvm/ExecutionEngine/Orc/ExecutionUtils.h>
#include <llvm/ExecutionEngine/Orc/JITTargetMachineBuilder.h>
#include <llvm/ExecutionEngine/Orc/LLJIT.h>
#include <llvm/IR/Constants.h>
#include <llvm/IR/Instructions.h>
#include <llvm/IR/Verifier.h>
#include <llvm/Passes/PassBuilder.h>
#include <llvm/Support/MemoryBuffer.h>
#include <llvm/Support/SHA256.h>
#include <llvm/Support/TargetSelect.h>
#include <llvm/Support/raw_ostream.h>
#include <llvm/Target/TargetMachine.h>

#include "jit/cpu/emitter.h"
#include "jit/cpu/perf_map.h"
#include "jit/cpu/simd_remarks.h"
#include "jit/device_program.h"
#include "jit/kernel_cache.h"
#include "runtime/math/math_functions.h"

#ifndef SIMIT_VERSION
#define SIMIT_VERSION "unknown"
#endif

namespace simit::jit {

namespace {

using cpu::Emitter;
using cpu::lanes_fit;

std::string message_of(llvm::Error e) { return llvm::toString(std::move(e)); }

// Compiled code calls the project's transcendental functions by their C names
// (jit/cpu/cpu_hooks.cpp), resolved here to this process's.
struct MathSymbol {
  const char* name;
  void* fn;
};
const MathSymbol kMathSymbols[] = {
    {"simit_math_exp", reinterpret_cast<void*>(&simit_math_exp)},
    {"simit_math_log", reinterpret_cast<void*>(&simit_math_log)},
    {"simit_math_pow", reinterpret_cast<void*>(&simit_math_pow)},
    {"simit_math_sin", reinterpret_cast<void*>(&simit_math_sin)},
    {"simit_math_cos", reinterpret_cast<void*>(&simit_math_cos)},
    {"simit_math_tan", reinterpret_cast<void*>(&simit_math_tan)},
    {"simit_math_asin", reinterpret_cast<void*>(&simit_math_asin)},
    {"simit_math_acos", reinterpret_cast<void*>(&simit_math_acos)},
    {"simit_math_atan2", reinterpret_cast<void*>(&simit_math_atan2)},
    {"simit_math_cbrt", reinterpret_cast<void*>(&simit_math_cbrt)},
    {"simit_math_atan2_x4", reinterpret_cast<void*>(&simit_math_atan2_x4)},
    {"simit_math_log_x4", reinterpret_cast<void*>(&simit_math_log_x4)},
    {"simit_math_atan2_x8", reinterpret_cast<void*>(&simit_math_atan2_x8)},
    {"simit_math_log_x8", reinterpret_cast<void*>(&simit_math_log_x8)},
};

// The C library's names of those functions, which kernels compiled by earlier versions
// called: never resolved, so that such a kernel from the cache fails to link and is compiled
// again (with the project's functions) rather than run with the C library's bits.
bool replaced_libm_name(llvm::StringRef name) {
  static const char* const kNames[] = {"sin",   "cos",  "tan", "asin", "acos",
                                       "atan2", "cbrt", "log", "exp",  "pow"};
  for (const char* n : kNames)
    if (name == n) return true;
  return false;
}

// This process's symbols (the C library's, the runtime's), which every JITDylib LLJIT makes
// links against: LLJIT's own process-symbols JITDylib, less the replaced C library names.
llvm::Expected<llvm::orc::JITDylibSP> process_symbols(llvm::orc::LLJIT& j) {
  auto gen = llvm::orc::DynamicLibrarySearchGenerator::GetForCurrentProcess(
      j.getDataLayout().getGlobalPrefix(),
      [](const llvm::orc::SymbolStringPtr& name) { return !replaced_libm_name(*name); });
  if (!gen) return gen.takeError();
  llvm::orc::JITDylib& jd = j.getExecutionSession().createBareJITDylib("<Process Symbols>");
  jd.addGenerator(std::move(*gen));
  return llvm::orc::JITDylibSP(&jd);
}

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

  // Object code for a module, from a target machine of its own (so that compiles on several
  // threads stay apart), at the host's best code generation or LLVM's fast one.
  llvm::Expected<std::unique_ptr<llvm::MemoryBuffer>> compile(llvm::Module& m, bool fast) {
    llvm::orc::JITTargetMachineBuilder jtmb = *jtmb_;
    if (fast) jtmb.setCodeGenOptLevel(llvm::CodeGenOptLevel::None);
    auto tm = jtmb.createTargetMachine();
    if (!tm) return tm.takeError();
    return llvm::orc::SimpleCompiler(**tm)(m);
  }

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
    jtmb_ = std::move(*jtmb);
    auto jit = llvm::orc::LLJITBuilder()
                   .setJITTargetMachineBuilder(*jtmb_)
                   .setProcessSymbolsJITDylibSetup(process_symbols)
                   .create();
    if (!jit) return message_of(jit.takeError());
    jit_ = std::move(*jit);
    cpu::add_perf_map(*jit_);
    // The project's transcendental functions, which every kernel links against (the main
    // JITDylib is in each kernel's link order).
    llvm::orc::SymbolMap math;
    for (const MathSymbol& m : kMathSymbols)
      math[jit_->mangleAndIntern(m.name)] = {
          llvm::orc::ExecutorAddr::fromPtr(m.fn),
          llvm::JITSymbolFlags::Exported | llvm::JITSymbolFlags::Callable};
    if (llvm::Error e = jit_->getMainJITDylib().define(llvm::orc::absoluteSymbols(std::move(math))))
      return message_of(std::move(e));
    return "";
  }

  std::optional<llvm::orc::JITTargetMachineBuilder> jtmb_;
  std::unique_ptr<llvm::orc::LLJIT> jit_;
  std::unique_ptr<llvm::TargetMachine> tm_;
};

// The compiled function's signatures (jit/target.h describes the arguments).
using MapFn = int32_t (*)(void* const* arrays, const double* scalars, const int32_t* endpoints,
                          int32_t begin, int32_t end, int32_t* failed_element);
using SystemFn = int32_t (*)(void* const* arrays, double* scalars, const int64_t* sizes,
                             const void* interrupt, void* pool, int64_t* iterations);

// A kernel's code lives in a JITDylib of its own: a cached object keeps the name its function
// had when it was compiled, and two kernels of the same key (two engines, two threads) may
// both be linked without their names meeting.
class CpuKernel : public Kernel {
 public:
  CpuKernel(llvm::orc::ExecutionSession& es, llvm::orc::JITDylib& jd) : es_(es), jd_(&jd) {}
  void* address = nullptr;
  bool system = false;
  bool device = false;  // a device program's steps (Emitter::run_device_steps)
  ~CpuKernel() override { llvm::consumeError(es_.removeJITDylib(*jd_)); }
  int32_t run(const MapArgs& a, ElementRange r, int32_t* failed) const override {
    return system ? 0
                  : reinterpret_cast<MapFn>(address)(a.arrays, a.scalars, a.endpoints, r.begin,
                                                     r.end, failed);
  }
  int32_t run(const SystemArgs& a) const override {
    if (device) throw std::logic_error("a device program runs through its executor's steps");
    int64_t uncounted = 0;
    return system ? reinterpret_cast<SystemFn>(address)(a.arrays, a.scalars, a.sizes, a.interrupt,
                                                        a.pool,
                                                        a.iterations ? a.iterations : &uncounted)
                  : 0;
  }
  void run_step(int32_t step, int64_t* context, int64_t first, int64_t end) const override {
    if (!device) return Kernel::run_step(step, context, first, end);
    reinterpret_cast<void (*)(int32_t, int64_t*, int64_t, int64_t)>(address)(step, context, first,
                                                                             end);
  }

 private:
  llvm::orc::ExecutionSession& es_;
  llvm::orc::JITDylib* jd_;
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

// Whether a constant converts an integer to a pointer: an address of this process built into
// the code (the emitter's calls into the host before they were made by name).
bool bakes_address(const llvm::Value* v) {
  const auto* c = llvm::dyn_cast<llvm::Constant>(v);
  if (!c || llvm::isa<llvm::GlobalValue>(c)) return false;
  if (const auto* ce = llvm::dyn_cast<llvm::ConstantExpr>(c);
      ce && ce->getOpcode() == llvm::Instruction::IntToPtr)
    return true;
  for (const llvm::Use& u : c->operands())
    if (bakes_address(u.get())) return true;
  return false;
}

// Whether the module's code is valid in another process: it names every host function it
// calls rather than holding its address.
bool relocatable(const llvm::Module& m) {
  for (const llvm::GlobalVariable& g : m.globals())
    if (g.hasInitializer() && bakes_address(g.getInitializer())) return false;
  for (const llvm::Function& f : m)
    for (const llvm::BasicBlock& bb : f)
      for (const llvm::Instruction& i : bb) {
        if (llvm::isa<llvm::IntToPtrInst>(i) && llvm::isa<llvm::Constant>(i.getOperand(0)))
          return false;
        for (const llvm::Use& u : i.operands())
          if (bakes_address(u.get())) return false;
      }
  return true;
}

class CpuTarget : public Target {
 public:
  CpuTarget(Session& s, const HostCalls& host, const std::string& cache_dir)
      : s_(s), host_(host), cache_(cache_dir) {}
  const char* name() const override { return "cpu"; }

  std::unique_ptr<Kernel> compile(const Trace& trace, bool keep_ir, std::string& error) override {
    std::string why_not;
    const bool large = node_count(trace) > kLargeTrace, lanes = lanes_fit(trace, &why_not);
    const int level = !large ? kOptLevel : lanes ? kLargeLanesTraceOptLevel : kLargeTraceOptLevel;
    const bool fast = large && !lanes && kLargeTraceFastCodegen;
    auto k = build(trace.name, key_of(trace), level, fast, lanes, keep_ir, error,
                   [&](llvm::Module& m, const std::string& name) {
                     return Emitter(trace, m, host_).run(name);
                   });
    if (k) {
      k->lanes = lanes ? cpu::lanes_of(trace) : 1;
      k->simd.map = true;
      k->simd.lanes = k->lanes;
      k->simd.lanes_why_not = why_not;
    }
    return k;
  }
  std::unique_ptr<Kernel> compile(const SystemTrace& trace, bool keep_ir,
                                  std::string& error) override {
    if (trace.device) {
      if (std::string why = device_refusal(trace); !why.empty()) {
        error = why;
        return nullptr;
      }
    }
    auto k = build(trace.name, key_of(trace), kOptLevel, false, false, keep_ir, error,
                   [&](llvm::Module& m, const std::string& name) {
                     return trace.device ? Emitter(trace, m).run_device_steps(name)
                                         : Emitter(trace, m).run_system(name);
                   });
    if (!k) return k;
    k->system = true;
    if (trace.device) {
      k->device = true;
      k->program = detached_device_program(trace);
    }
    return k;
  }

 private:
  // The trace's key text, needed only with a cache.
  template <class T>
  std::string key_of(const T& trace) const {
    return cache_.enabled() ? kernel_key_text(trace) : "";
  }

  // The cache key: the trace's key text and everything else that decides its object code.
  std::string digest_of(const std::string& trace_key, int level, bool fast) const {
    llvm::SHA256 sha;
    const std::string head = "simit kernel format " + std::to_string(kKernelFormatVersion) +
                             "\nsimit " SIMIT_VERSION "\nllvm " LLVM_VERSION_STRING "\ntriple " +
                             s_.target().getTargetTriple().str() + "\ncpu " +
                             s_.target().getTargetCPU().str() + "\nfeatures " +
                             s_.target().getTargetFeatureString().str() + "\nopt " +
                             std::to_string(level) + (fast ? " fast" : "") + "\nlanes " +
                             std::to_string(kLanes) + " " + std::to_string(kLanes32) + "\n";
    sha.update(head);
    sha.update(trace_key);
    const std::array<uint8_t, 32> d = sha.final();
    return std::string(d.begin(), d.end());
  }

  // Links object code into a JITDylib of its own, in which the host functions the code calls
  // by name resolve to this process's (the main JITDylib's generator finds the C library's).
  // `label` (the trace's name) follows the JITDylib's own name, after a colon, for the perf
  // map's names (jit/cpu/perf_map.h).
  std::unique_ptr<CpuKernel> link(const std::string& symbol, const std::string& label,
                                  std::unique_ptr<llvm::MemoryBuffer> obj, std::string& error) {
    static std::atomic<uint64_t> serial{0};
    llvm::orc::LLJIT& jit = s_.jit();
    auto jd = jit.createJITDylib("simit_kernel_" + std::to_string(serial++) + ":" + label);
    if (!jd) {
      error = message_of(jd.takeError());
      return nullptr;
    }
    jd->addToLinkOrder(jit.getMainJITDylib());
    auto k = std::make_unique<CpuKernel>(jit.getExecutionSession(), *jd);
    if (host_.decompose) {
      llvm::orc::SymbolMap calls;
      calls[jit.mangleAndIntern("simit_jit_decompose")] = {
          llvm::orc::ExecutorAddr::fromPtr(host_.decompose),
          llvm::JITSymbolFlags::Exported | llvm::JITSymbolFlags::Callable};
      if (host_.parallel_for)
        calls[jit.mangleAndIntern("simit_jit_parallel_for")] = {
            llvm::orc::ExecutorAddr::fromPtr(host_.parallel_for),
            llvm::JITSymbolFlags::Exported | llvm::JITSymbolFlags::Callable};
      if (llvm::Error e = jd->define(llvm::orc::absoluteSymbols(std::move(calls)))) {
        error = message_of(std::move(e));
        return nullptr;
      }
    }
    if (llvm::Error e = jit.addObjectFile(*jd, std::move(obj))) {
      error = message_of(std::move(e));
      return nullptr;
    }
    auto sym = jit.lookup(*jd, symbol);
    if (!sym) {
      error = message_of(sym.takeError());
      return nullptr;
    }
    k->address = sym->toPtr<void*>();
    return k;
  }

  // The kernel from the cache when it holds one (and the IR is not asked for); otherwise
  // emits a function into a new module, optimises it for the host (collecting what the
  // vectorisers did with its loops: `lanes`, a map kernel in lanes), compiles it, keeps the
  // object and that report in the cache, and links it.
  std::unique_ptr<CpuKernel> build(
      const std::string& label, const std::string& trace_key, int level, bool fast, bool lanes,
      bool keep_ir, std::string& error,
      const std::function<llvm::Function*(llvm::Module&, const std::string&)>& emit) {
    const auto start = std::chrono::steady_clock::now();
    const auto elapsed_ms = [&] {
      return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
          .count();
    };
    const std::string digest = cache_.enabled() ? digest_of(trace_key, level, fast) : "";
    if (cache_.enabled() && !keep_ir) {
      if (std::optional<CacheEntry> entry = cache_.load(digest)) {
        // An entry that does not link, or whose report does not read, is compiled again.
        std::string link_error;
        SimdReport simd;
        auto k = read_simd_report(entry->simd, simd)
                     ? link(entry->symbol, label,
                            llvm::MemoryBuffer::getMemBufferCopy(entry->object, entry->symbol),
                            link_error)
                     : nullptr;
        if (k) {
          k->simd = std::move(simd);
          k->cached = true;
          k->compile_ms = elapsed_ms();
          return k;
        }
      }
    }
    // The function's name: the key's (stable, so a cached object and its lookup agree), or a
    // serial number without a cache.
    static std::atomic<uint64_t> serial{0};
    const std::string name = cache_.enabled() ? "simit_k_" + hex_of(digest.substr(0, 8))
                                              : "simit_kernel_" + std::to_string(serial++);
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
    const bool keep = cache_.enabled() && relocatable(*mod);
    // The vectorisers run from -O2 on (optimise); their remarks are kept while they do.
    SimdReport simd;
    simd.reported = true;
    simd.vectorisers = level >= 2;
    if (simd.vectorisers) {
      cpu::SimdRemarks remarks(*mod, lanes);
      ctx->setDiagnosticHandler(remarks.handler());
      optimise(*mod, s_.target(), level);
      ctx->setDiagnosticHandler(std::make_unique<llvm::DiagnosticHandler>());
      remarks.fill(simd);
    } else if (level > 0) {
      optimise(*mod, s_.target(), level);
    }
    std::string ir;
    if (keep_ir) {
      llvm::raw_string_ostream os(ir);
      // What the vectorisers did with each loop, above the module (its loops carry their
      // numbers as "simit.loop" metadata).
      for (const SimdLoop& l : simd.loops) os << "; " << cpu::SimdRemarks::describe(l) << "\n";
      mod->print(os, nullptr);
    }
    auto obj = s_.compile(*mod, fast);
    if (!obj) {
      error = message_of(obj.takeError());
      return nullptr;
    }
    if (keep) {
      // A cache that cannot be written is no cache for this kernel: nothing is reported.
      std::string store_error;
      cache_.store(digest, CacheEntry{name, (*obj)->getBuffer().str(), simd_report_text(simd)},
                   store_error);
    }
    auto k = link(name, label, std::move(*obj), error);
    if (!k) return nullptr;
    k->llvm_ir = std::move(ir);
    k->simd = std::move(simd);
    k->compile_ms = elapsed_ms();
    return k;
  }

  Session& s_;
  HostCalls host_;
  KernelCache cache_;
};

}  // namespace

std::unique_ptr<Target> make_cpu_target(const HostCalls& host, const std::string& cache_dir,
                                        std::string& error) {
  Session* s = Session::get(error);
  if (!s) return nullptr;
  return std::make_unique<CpuTarget>(*s, host, cache_dir);
}

}  // namespace simit::jit
