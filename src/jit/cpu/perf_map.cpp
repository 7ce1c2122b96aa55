// The perf map listing (jit/cpu/perf_map.h): a JITLink plugin that writes each linked
// function's address, size and name once its addresses are final, one line per function, as
// perf's "START SIZE symbolname" format asks (hexadecimal, no 0x). The name is the trace's
// (the kernel's JITDylib carries it after a colon), then the function's own in brackets:
// "tet_force:164 [simit_k_5568246e66f870c5]",
// "statements:122-136 [simit_k_0a980c92aedb7de0.op2]"
// (a solver loop's passes are functions of their own; --dump llvm shows them by that name).
//
// JITLink keeps no names for an object's local symbols, and a solver loop's passes are local
// functions (`simit_k_....op2`), so the names come from the object's own symbol table, read
// before the link: each function's section and offset there, placed at its section's address
// once the link has laid the sections out.
#include "jit/cpu/perf_map.h"

#include <unistd.h>

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include <llvm/ExecutionEngine/JITLink/JITLink.h>
#include <llvm/ExecutionEngine/Orc/ObjectLinkingLayer.h>
#include <llvm/Object/ELFObjectFile.h>

namespace simit::jit::cpu {

namespace {

struct Function {
  std::string name, section;
  uint64_t offset = 0, size = 0;
};

// Whether SIMIT_PERF_MAP asks for the listing: set, and neither "" nor "0".
bool wanted() {
  const char* want = std::getenv("SIMIT_PERF_MAP");
  return want && *want && std::strcmp(want, "0") != 0;
}

class PerfMapPlugin : public llvm::orc::ObjectLinkingLayer::Plugin {
 public:
  ~PerfMapPlugin() override {
    if (file_) std::fclose(file_);
  }

  void notifyMaterializing(llvm::orc::MaterializationResponsibility& mr,
                           llvm::jitlink::LinkGraph& g, llvm::jitlink::JITLinkContext&,
                           llvm::MemoryBufferRef object) override {
    if (!wanted()) return;
    const std::string& dylib = mr.getTargetJITDylib().getName();
    const size_t colon = dylib.find(':');
    const std::string label = colon == std::string::npos ? "" : dylib.substr(colon + 1);
    std::vector<Function> functions;
    auto file = llvm::object::ObjectFile::createObjectFile(object);
    if (!file) return llvm::consumeError(file.takeError());
    if (!llvm::isa<llvm::object::ELFObjectFileBase>(file->get())) return;  // perf: Linux only
    for (const llvm::object::SymbolRef& sym : (*file)->symbols()) {
      auto type = sym.getType();
      auto name = sym.getName();
      auto section = sym.getSection();
      auto value = sym.getValue();
      if (!type || !name || !section || !value || *type != llvm::object::SymbolRef::ST_Function ||
          *section == (*file)->section_end()) {
        if (!type) llvm::consumeError(type.takeError());
        if (!name) llvm::consumeError(name.takeError());
        if (!section) llvm::consumeError(section.takeError());
        if (!value) llvm::consumeError(value.takeError());
        continue;
      }
      auto section_name = (*section)->getName();
      if (!section_name) {
        llvm::consumeError(section_name.takeError());
        continue;
      }
      functions.push_back({label.empty() ? name->str() : label + " [" + name->str() + "]",
                           section_name->str(), *value, llvm::object::ELFSymbolRef(sym).getSize()});
    }
    std::lock_guard<std::mutex> lock(mutex_);
    pending_[&g] = std::move(functions);
  }

  void modifyPassConfig(llvm::orc::MaterializationResponsibility&, llvm::jitlink::LinkGraph&,
                        llvm::jitlink::PassConfiguration& config) override {
    config.PostFixupPasses.push_back([this](llvm::jitlink::LinkGraph& g) {
      std::lock_guard<std::mutex> lock(mutex_);  // kernels link on several threads
      auto it = pending_.find(&g);
      if (it == pending_.end()) return llvm::Error::success();
      // The file of this process (a child after fork() has a file of its own).
      if (!file_ || pid_ != getpid()) {
        if (file_) std::fclose(file_);
        pid_ = getpid();
        // A file left by an earlier process of the same number is not this one's: replaced.
        file_ = std::fopen(perf_map_path().c_str(), "w");
      }
      if (!file_) {  // no listing, and no error: the run does not depend on it
        pending_.erase(it);
        return llvm::Error::success();
      }
      for (const Function& f : it->second) {
        // JITLink makes each section of an ELF object one block, so a function lies at its
        // section's block plus its offset there; a section it split otherwise is left out.
        llvm::jitlink::Section* s = g.findSectionByName(f.section);
        if (!s || s->blocks_size() != 1 || f.size == 0) continue;
        const uint64_t start = (*s->blocks().begin())->getAddress().getValue() + f.offset;
        std::fprintf(file_, "%" PRIx64 " %" PRIx64 " %s\n", start, f.size, f.name.c_str());
      }
      pending_.erase(it);
      // Written at once: perf reads the file after the run, which may end by a signal.
      std::fflush(file_);
      return llvm::Error::success();
    });
  }
  llvm::Error notifyFailed(llvm::orc::MaterializationResponsibility&) override {
    return llvm::Error::success();
  }
  llvm::Error notifyRemovingResources(llvm::orc::JITDylib&, llvm::orc::ResourceKey) override {
    return llvm::Error::success();
  }
  void notifyTransferringResources(llvm::orc::JITDylib&, llvm::orc::ResourceKey,
                                   llvm::orc::ResourceKey) override {}

 private:
  std::FILE* file_ = nullptr;
  pid_t pid_ = 0;
  std::mutex mutex_;
  std::map<const llvm::jitlink::LinkGraph*, std::vector<Function>> pending_;
};

}  // namespace

std::string perf_map_path() { return "/tmp/perf-" + std::to_string(getpid()) + ".map"; }

void add_perf_map(llvm::orc::LLJIT& jit) {
  if (auto* layer = llvm::dyn_cast<llvm::orc::ObjectLinkingLayer>(&jit.getObjLinkingLayer()))
    layer->addPlugin(std::make_unique<PerfMapPlugin>());
}

}  // namespace simit::jit::cpu
