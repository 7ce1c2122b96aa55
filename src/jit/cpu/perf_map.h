// Names for compiled kernels in `perf report`: with SIMIT_PERF_MAP set, every function the
// CPU code generator links is listed in /tmp/perf-PID.map, the file Linux perf reads for code
// it finds no object file for (docs/jit.md, "Profiling compiled kernels").
#pragma once

#include <string>

#include <llvm/ExecutionEngine/Orc/LLJIT.h>

namespace simit::jit::cpu {

// Adds the listing to `jit`'s object linking layer. Each kernel linked while SIMIT_PERF_MAP
// is set to anything but "" or "0" is listed (the variable is read at each link, so a test
// or a host may set it late); a file that cannot be opened lists nothing, silently.
void add_perf_map(llvm::orc::LLJIT& jit);
// The file: /tmp/perf-PID.map, where perf looks for it.
std::string perf_map_path();

}  // namespace simit::jit::cpu
