// The device bitcode of the project's math functions linked into PTX modules
// (jit/ptx/device_math.h).
#include "jit/ptx/device_math.h"

#include <cstddef>
#include <memory>
#include <mutex>

#include <llvm/Bitcode/BitcodeReader.h>
#include <llvm/ExecutionEngine/Orc/LLJIT.h>
#include <llvm/ExecutionEngine/Orc/ThreadSafeModule.h>
#include <llvm/IR/Module.h>
#include <llvm/Linker/Linker.h>
#include <llvm/Support/Error.h>
#include <llvm/Support/MemoryBufferRef.h>
#include <llvm/Support/TargetSelect.h>

namespace simit::jit::ptx {

#ifdef SIMIT_WITH_DEVICE_MATH
// The generated device_math_bitcode.cpp.
extern const unsigned char kDeviceMathBitcode[];
extern const std::size_t kDeviceMathBitcodeSize;
#endif

bool device_math_available() {
#ifdef SIMIT_WITH_DEVICE_MATH
  return true;
#else
  return false;
#endif
}

#ifdef SIMIT_WITH_DEVICE_MATH
namespace {

// The bitcode as a module of `ctx`, without clang's target attributes (the machine that
// compiles it decides); null with `error`.
std::unique_ptr<llvm::Module> parse(llvm::LLVMContext& ctx, std::string& error) {
  const llvm::StringRef bytes(reinterpret_cast<const char*>(kDeviceMathBitcode),
                              kDeviceMathBitcodeSize);
  llvm::Expected<std::unique_ptr<llvm::Module>> parsed =
      llvm::parseBitcodeFile(llvm::MemoryBufferRef(bytes, "device_math"), ctx);
  if (!parsed) {
    error = "the device math bitcode cannot be read: " + llvm::toString(parsed.takeError());
    return nullptr;
  }
  for (llvm::Function& f : **parsed) {
    f.removeFnAttr("target-cpu");
    f.removeFnAttr("target-features");
  }
  return std::move(*parsed);
}

}  // namespace
#endif

bool link_device_math(llvm::Module& m, std::string& error) {
#ifndef SIMIT_WITH_DEVICE_MATH
  (void)m, (void)error;
  return true;
#else
  bool calls_math = false;
  for (const llvm::Function& f : m)
    if (f.isDeclaration() && f.getName().starts_with("simit_math_")) calls_math = true;
  if (!calls_math) return true;
  // clang's per-function target attributes (its default architecture and PTX version) would
  // keep the inliner from merging them into the kernel, and the kernel's machine decides both:
  // parse() drops them.
  std::unique_ptr<llvm::Module> math = parse(m.getContext(), error);
  if (!math) return false;
  math->setTargetTriple(m.getTargetTriple());
  math->setDataLayout(m.getDataLayout());
  // Only what the module calls, and what that calls in turn.
  if (llvm::Linker::linkModules(m, std::move(math), llvm::Linker::Flags::LinkOnlyNeeded)) {
    error = "the device math bitcode cannot be linked into the kernel's module";
    return false;
  }
  // Everything but the kernels is the module's own: the optimiser may inline it, and drops
  // what is left unused (the tables of functions it does not call).
  for (llvm::Function& f : m)
    if (!f.isDeclaration() && f.getCallingConv() != llvm::CallingConv::PTX_Kernel)
      f.setLinkage(llvm::GlobalValue::InternalLinkage);
  for (llvm::GlobalVariable& g : m.globals())
    if (!g.isDeclaration()) g.setLinkage(llvm::GlobalValue::InternalLinkage);
  return true;
#endif
}

void* device_math_on_host(const std::string& name, std::string& error) {
#ifndef SIMIT_WITH_DEVICE_MATH
  (void)name;
  error = "this build has no device math bitcode";
  return nullptr;
#else
  static std::once_flag once;
  static std::unique_ptr<llvm::orc::LLJIT> jit;
  static std::string failure;
  std::call_once(once, [] {
    llvm::InitializeNativeTarget();
    llvm::InitializeNativeTargetAsmPrinter();
    auto message = [](llvm::Error e) { return llvm::toString(std::move(e)); };
    auto jtmb = llvm::orc::JITTargetMachineBuilder::detectHost();
    if (!jtmb) return void(failure = message(jtmb.takeError()));
    // As the CPU target: no fused multiply-add, whatever the host offers.
    jtmb->getOptions().AllowFPOpFusion = llvm::FPOpFusion::Strict;
    jtmb->getFeatures().AddFeature("fma", false);
    jtmb->getFeatures().AddFeature("avx512f", false);
    auto made = llvm::orc::LLJITBuilder().setJITTargetMachineBuilder(std::move(*jtmb)).create();
    if (!made) return void(failure = message(made.takeError()));
    auto ctx = std::make_unique<llvm::LLVMContext>();
    std::unique_ptr<llvm::Module> math = parse(*ctx, failure);
    if (!math) return;
    math->setTargetTriple((*made)->getTargetTriple().str());
    math->setDataLayout((*made)->getDataLayout());
    if (llvm::Error e =
            (*made)->addIRModule(llvm::orc::ThreadSafeModule(std::move(math), std::move(ctx))))
      return void(failure = message(std::move(e)));
    jit = std::move(*made);
  });
  if (!jit) {
    error = "the device math bitcode cannot be compiled for the host: " + failure;
    return nullptr;
  }
  auto sym = jit->lookup(name);
  if (!sym) {
    error = "the device math bitcode has no " + name + ": " + llvm::toString(sym.takeError());
    return nullptr;
  }
  return sym->toPtr<void*>();
#endif
}

}  // namespace simit::jit::ptx
