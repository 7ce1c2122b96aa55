// libFuzzer target of the Wavefront OBJ reader: the input is one .obj file.
#include "mesh_fuzz.h"
#include "runtime/mesh/obj_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace simit::fuzz;
  std::string path = write_scratch("m.obj", as_text(data, size));
  read_and_check("obj_fuzz", path, simit::runtime::read_obj);
  return 0;
}
