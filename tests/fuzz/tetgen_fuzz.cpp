// libFuzzer target of the TetGen reader: the input is BASE.node, then BASE.ele, BASE.face and
// BASE.edge, each part after an '@' byte (a missing part is a missing file).
#include <array>

#include "mesh_fuzz.h"
#include "runtime/mesh/tetgen_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace simit::fuzz;
  static const std::array<const char*, 4> kFiles = {"m.node", "m.ele", "m.face", "m.edge"};
  std::vector<std::string_view> parts = split_parts(as_text(data, size), '@', kFiles.size());
  for (size_t i = 0; i < kFiles.size(); ++i) {
    if (i < parts.size())
      write_scratch(kFiles[i], parts[i]);
    else
      remove_scratch(kFiles[i]);
  }
  read_and_check("tetgen_fuzz", scratch_folder() + "/m.node", simit::runtime::read_tetgen);
  return 0;
}
