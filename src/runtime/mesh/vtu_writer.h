// Writer of ParaView/VTK XML unstructured grids (.vtu) with raw binary appended data.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

// One named data array: `components` values per point (or cell), one point after another;
// 1 for a scalar field, 3 for a vector field. The values are only viewed, not copied.
struct VtuArray {
  std::string name;
  int components = 1;
  std::variant<std::span<const double>, std::span<const int32_t>> values;
};

// Writes `mesh` to `path`: every tet, then every triangle, then every edge is one cell, so a
// cell array has one entry per cell in that order. Data arrays are Float64 or Int32, stored
// raw after the XML header (header_type UInt64). Sizes and indices are checked first; the file
// appears complete (written under a temporary name, then renamed) or not at all. Throws
// MeshError naming the file and the faulty array.
void write_vtu(const std::string& path, const Mesh& mesh, const std::vector<VtuArray>& point_data,
               const std::vector<VtuArray>& cell_data);

// Writes the .pvtu at `path` that joins `pieces` (.vtu files of one frame, one per MPI rank,
// named relative to the .pvtu's folder) into one dataset: the arrays declared as `point_data`
// and `cell_data` declare them (their values are not read; every piece holds them).
void write_pvtu(const std::string& path, const std::vector<std::string>& pieces,
                const std::vector<VtuArray>& point_data, const std::vector<VtuArray>& cell_data);

// XML attribute text with &, <, >, " and ' escaped.
std::string xml_escape(const std::string& text);

}  // namespace simit::runtime
