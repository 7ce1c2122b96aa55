// libFuzzer target of the Gmsh reader: the input is one .msh file.
#include "mesh_fuzz.h"
#include "runtime/mesh/gmsh_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace simit::fuzz;
  std::string path = write_scratch("m.msh", as_text(data, size));
  read_and_check("gmsh_fuzz", path, simit::runtime::read_gmsh);
  return 0;
}
