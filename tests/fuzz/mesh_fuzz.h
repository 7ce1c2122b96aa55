// The invariants the mesh-reader harnesses check: a file is read, or rejected with a MeshError
// that names it; what is read has every vertex index in range and passes or fails
// check_mesh with a MeshError too. Anything else thrown escapes and is a crash.
#pragma once

#include <string>

#include "fuzz_support.h"
#include "runtime/mesh/mesh.h"

namespace simit::fuzz {

template <class Read>
void read_and_check(const char* harness, const std::string& path, Read read) {
  runtime::Mesh mesh;
  try {
    mesh = read(path);
  } catch (const runtime::MeshError& e) {
    if (std::string(e.what()).rfind(scratch_folder(), 0) != 0)
      invariant_broken(harness, std::string("the error does not name the file: ") + e.what());
    note_rejected(harness, e.what());
    return;
  }
  try {
    runtime::check_indices(mesh);
  } catch (const runtime::MeshError& e) {
    invariant_broken(harness, std::string("the reader let a bad index through: ") + e.what());
  }
  try {
    runtime::check_mesh(mesh, path);
    runtime::orient_tets(mesh);
  } catch (const runtime::MeshError& e) {
    note_rejected(harness, e.what());
  }
}

}  // namespace simit::fuzz
