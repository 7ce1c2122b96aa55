// The device bitcode of the project's math functions linked into PTX modules
// (jit/ptx/device_math.h).
#include "jit/ptx/device_math.h"

#include <cstddef>
#include <memory>

#include <llvm/Bitcode/BitcodeReader.h>
#include <llvm/IR/Module.h>
#include <llvm/Linker/Linker.h>
#include <llvm/Support/Error.h>
#include <llvm/Support/MemoryBufferRef.h>

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

bool link_device_math(llvm::Module& m, std::string& error) {
#ifndef SIMIT_WITH_DEVICE_MATH
  (void)m, (void)error;
  return true;
#else
  bool calls_math = false;
  for (const llvm::Function& f : m)
    if (f.isDeclaration() && f.getName().starts_with("simit_math_")) calls_math = true;
  if (!calls_math) return true;
  const llvm::StringRef bytes(reinterpret_cast<const char*>(kDeviceMathBitcode),
                              kDeviceMathBitcodeSize);
  llvm::Expected<std::unique_ptr<llvm::Module> > parsed =
      llvm::parseBitcodeFile(llvm::MemoryBufferRef(bytes, "device_math"), m.getContext());
  if (!parsed) {
    error = "the device math bitcode cannot be read: " + llvm::toString(parsed.takeError());
    return false;
  }
  std::unique_ptr<llvm::Module> math = std::move(*parsed);
  math->setTargetTriple(m.getTargetTriple());
  math->setDataLayout(m.getDataLayout());
  // clang's per-function target attributes (its default architecture and PTX version) would
  // keep the inliner from merging them into the kernel, and the kernel's machine decides both.
  for (llvm::Function& f : *math) {
    f.removeFnAttr("target-cpu");
    f.removeFnAttr("target-features");
  }
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

}  // namespace simit::jit::ptx
