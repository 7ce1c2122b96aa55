// The NVIDIA GPU target (jit/ptx/ptx_target.h): loop IR to LLVM IR through the shared
// emission with the GPU's hooks, optimised and turned into PTX text by LLVM's NVPTX back end
// for `nvptx64-nvidia-cuda`. Floating-point fusion stays off (FPOpFusion::Strict, no
// `contract` flag anywhere), so every multiplication and addition is its own correctly
// rounded `mul.rn.f64` / `add.rn.f64`, which ptxas may not fuse into an fma.
#include "jit/ptx/ptx_target.h"

#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>

#include <llvm/IR/CallingConv.h>
#include <llvm/IR/LegacyPassManager.h>
#include <llvm/IR/Verifier.h>
#include <llvm/MC/MCSubtargetInfo.h>
#include <llvm/MC/TargetRegistry.h>
#include <llvm/Passes/PassBuilder.h>
#include <llvm/Support/TargetSelect.h>
#include <llvm/Support/raw_ostream.h>
#include <llvm/Target/TargetMachine.h>
#include <llvm/Target/TargetOptions.h>

#include "jit/device_program.h"
#include "jit/llvm/emitter.h"
#include "jit/ptx/device_math.h"
#include "jit/ptx/ptx_hooks.h"
#include "jit/tunables.h"

namespace simit::jit::ptx {

namespace {

constexpr const char* kTriple = "nvptx64-nvidia-cuda";

bool calls_runtime(const std::vector<Stmt>& body) {
  for (const Stmt& s : body)
    if (s.kind == StmtKind::Decompose || calls_runtime(s.body) || calls_runtime(s.orelse))
      return true;
  return false;
}

// LLVM's NVPTX back end, registered once; "" or why it is missing.
const llvm::Target* nvptx(std::string& error) {
#ifndef SIMIT_WITH_NVPTX
  error = "this build's LLVM has no NVPTX back end";
  return nullptr;
#else
  static std::once_flag once;
  std::call_once(once, [] {
    LLVMInitializeNVPTXTargetInfo();
    LLVMInitializeNVPTXTarget();
    LLVMInitializeNVPTXTargetMC();
    LLVMInitializeNVPTXAsmPrinter();
  });
  std::string why;
  const llvm::Target* t = llvm::TargetRegistry::lookupTarget(kTriple, why);
  if (!t) error = "LLVM has no NVPTX back end: " + why;
  return t;
#endif
}

// As the CPU target: LLVM's pipeline at `level` (0: none).
void optimise(llvm::Module& m, llvm::TargetMachine& tm, int level) {
  if (level <= 0) return;
  llvm::LoopAnalysisManager lam;
  llvm::FunctionAnalysisManager fam;
  llvm::CGSCCAnalysisManager cgam;
  llvm::ModuleAnalysisManager mam;
  llvm::PassBuilder pb(&tm);  // the NVPTX passes (NVVMReflect, ...) come with the machine
  pb.registerModuleAnalyses(mam);
  pb.registerCGSCCAnalyses(cgam);
  pb.registerFunctionAnalyses(fam);
  pb.registerLoopAnalyses(lam);
  pb.crossRegisterProxies(lam, fam, cgam, mam);
  const llvm::OptimizationLevel o = level >= 3   ? llvm::OptimizationLevel::O3
                                    : level == 2 ? llvm::OptimizationLevel::O2
                                                 : llvm::OptimizationLevel::O1;
  pb.buildPerModuleDefaultPipeline(o).run(m, mam);
}

class PtxTarget : public Target {
 public:
  PtxTarget(const llvm::Target& t, std::string arch) : t_(t), arch_(std::move(arch)) {}
  const char* name() const override { return "ptx"; }

  std::unique_ptr<Kernel> compile(const Trace& trace, bool keep_ir, std::string& error) override {
    if (std::string why = gpu_refusal(trace); !why.empty()) {
      error = why;
      return nullptr;
    }
    const auto start = std::chrono::steady_clock::now();
    std::unique_ptr<llvm::TargetMachine> tm = machine(node_count(trace) > kLargeTrace);
    if (!tm) {
      error = "LLVM could not make a target machine for " + arch_;
      return nullptr;
    }
    llvm::LLVMContext ctx;
    llvm::Module m(kMapEntry, ctx);
    m.setTargetTriple(kTriple);
    m.setDataLayout(tm->createDataLayout());
    PtxHooks hooks;
    codegen::MapEmitter(trace, m, hooks).run(kMapEntry);
    if (!hooks.refused().empty()) {
      error = hooks.refused();
      return nullptr;
    }
    auto k = std::make_unique<PtxKernel>();
    if (!finish(m, *tm, *k, keep_ir, node_count(trace) > kLargeTrace, error)) return nullptr;
    k->entry = kMapEntry;
    k->compile_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return k;
  }

  // A device program (SystemTrace::device): each step a kernel of one unit per thread.
  std::unique_ptr<Kernel> compile(const SystemTrace& trace, bool keep_ir,
                                  std::string& error) override {
    if (std::string why = gpu_refusal(trace); !why.empty()) {
      error = why;
      return nullptr;
    }
    const auto start = std::chrono::steady_clock::now();
    std::unique_ptr<llvm::TargetMachine> tm = machine(false);
    if (!tm) {
      error = "LLVM could not make a target machine for " + arch_;
      return nullptr;
    }
    llvm::LLVMContext ctx;
    llvm::Module m(kStepEntry, ctx);
    m.setTargetTriple(kTriple);
    m.setDataLayout(tm->createDataLayout());
    PtxHooks hooks;
    std::unique_ptr<codegen::TargetHooks> step_hooks = codegen::device_step_hooks(hooks);
    const DeviceProgram program = plan_device_program(trace);
    const std::vector<llvm::Function*> steps =
        codegen::SystemEmitter(trace, m, *step_hooks).device_steps(program, "simit_step_body");
    auto k = std::make_unique<PtxKernel>();
    for (size_t i = 0; i < steps.size(); ++i)
      k->entries.push_back(step_kernel(m, *steps[i], device_step_name(kStepEntry, i)));
    if (!hooks.refused().empty()) {
      error = hooks.refused();
      return nullptr;
    }
    if (!finish(m, *tm, *k, keep_ir, false, error)) return nullptr;
    k->program = detached_device_program(trace);
    k->compile_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return k;
  }

 private:
  // Verifies the module, links the project's math functions from their device bitcode (the
  // same sources as the host's, so the module is whole and computes the host's bits),
  // optimises it (not a large trace, as on the CPU: jit/tunables.h) and emits its PTX.
  static bool finish(llvm::Module& m, llvm::TargetMachine& tm, PtxKernel& k, bool keep_ir,
                     bool large, std::string& error) {
    std::string broken;
    llvm::raw_string_ostream bs(broken);
    if (llvm::verifyModule(m, &bs)) {
      error = "LLVM rejected the generated code: " + bs.str();
      return false;
    }
    if (!link_device_math(m, error)) return false;
    optimise(m, tm, large ? 0 : kOptLevel);
    if (keep_ir) {
      llvm::raw_string_ostream os(k.llvm_ir);
      m.print(os, nullptr);
    }
    llvm::SmallString<0> text;
    llvm::raw_svector_ostream os(text);
    llvm::legacy::PassManager pm;
    if (tm.addPassesToEmitFile(pm, os, nullptr, llvm::CodeGenFileType::AssemblyFile)) {
      error = "LLVM's NVPTX back end cannot emit PTX text";
      return false;
    }
    pm.run(m);
    k.ptx = text.str().str();
    return true;
  }

  // The kernel `name`(int64_t* context, int64_t units) around a step: the unit of the thread's
  // index (ptx_hooks.h) when it is below `units`.
  static std::string step_kernel(llvm::Module& m, llvm::Function& step, const std::string& name) {
    llvm::LLVMContext& ctx = m.getContext();
    llvm::IRBuilder<> b(ctx);
    llvm::Type* i64 = b.getInt64Ty();
    auto* ft = llvm::FunctionType::get(b.getVoidTy(), {b.getPtrTy(), i64}, false);
    auto* fn = llvm::Function::Create(ft, llvm::Function::ExternalLinkage, name, m);
    fn->setCallingConv(llvm::CallingConv::PTX_Kernel);
    step.addFnAttr(llvm::Attribute::AlwaysInline);
    auto* entry = llvm::BasicBlock::Create(ctx, "entry", fn);
    auto* run = llvm::BasicBlock::Create(ctx, "unit", fn);
    auto* done = llvm::BasicBlock::Create(ctx, "done", fn);
    b.SetInsertPoint(entry);
    llvm::Value* u = thread_index(b);
    b.CreateCondBr(b.CreateICmpSLT(u, fn->getArg(1)), run, done);
    b.SetInsertPoint(run);
    b.CreateCall(&step, {fn->getArg(0), u, b.CreateAdd(u, b.getInt64(1))});
    b.CreateBr(done);
    b.SetInsertPoint(done);
    b.CreateRetVoid();
    return name;
  }

  // A machine of its own per compile (compiles on several threads stay apart).
  std::unique_ptr<llvm::TargetMachine> machine(bool large) const {
    llvm::TargetOptions options;
    options.AllowFPOpFusion = llvm::FPOpFusion::Strict;  // the arithmetic contract: no fma
    const llvm::CodeGenOptLevel level =
        large ? llvm::CodeGenOptLevel::Less : llvm::CodeGenOptLevel::Default;
    return std::unique_ptr<llvm::TargetMachine>(
        t_.createTargetMachine(kTriple, arch_, "", options, std::nullopt, std::nullopt, level));
  }

  const llvm::Target& t_;
  std::string arch_;
};

}  // namespace

int32_t PtxKernel::run(const MapArgs&, ElementRange, int32_t*) const {
  throw std::logic_error("a PTX kernel runs on the GPU, through the CUDA driver (not built yet)");
}

int32_t PtxKernel::run(const SystemArgs&) const {
  throw std::logic_error("a PTX kernel runs on the GPU, through the CUDA driver (not built yet)");
}

std::string gpu_refusal(const Trace& t) {
  if (calls_runtime(t.body))
    return "calls the runtime's simit_jit_decompose, which has no device version yet";
  return "";
}

std::string gpu_refusal(const SystemTrace& t) {
  if (!t.device) return "not lowered as a device program";
  return device_refusal(t);
}

std::unique_ptr<Target> make_ptx_target(const std::string& gpu_arch, std::string& error) {
  const llvm::Target* t = nvptx(error);
  if (!t) return nullptr;
  // Asked of a subtarget of a known architecture: one of an unknown one would print LLVM's
  // warning about it.
  std::unique_ptr<llvm::MCSubtargetInfo> sti(
      t->createMCSubtargetInfo(kTriple, kDefaultGpuArch, ""));
  if (!sti || !sti->isCPUStringValid(gpu_arch)) {
    error = "unknown GPU architecture '" + gpu_arch +
            "' (LLVM's NVPTX back end knows sm_XX, e.g. " + kDefaultGpuArch + ")";
    return nullptr;
  }
  return std::make_unique<PtxTarget>(*t, gpu_arch);
}

}  // namespace simit::jit::ptx
