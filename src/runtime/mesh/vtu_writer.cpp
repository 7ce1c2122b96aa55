// .vtu writing: an XML header whose DataArrays point into one appended block of raw arrays,
// each preceded by its byte count
// (https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html).
#include "runtime/mesh/vtu_writer.h"

#include <bit>
#include <set>
#include <sstream>

#include "runtime/mesh/atomic_file.h"

namespace simit::runtime {

namespace {

static_assert(sizeof(Point) == 3 * sizeof(double) && sizeof(Tet) == 4 * sizeof(int32_t),
              "mesh arrays are written as packed raw blocks");

constexpr uint8_t kVtkLine = 3, kVtkTriangle = 5, kVtkTetra = 10;

// One DataArray: its XML attributes and the raw pieces that make up its appended bytes.
struct Block {
  std::string attributes;
  std::vector<std::span<const char>> parts;
  uint64_t bytes() const {
    uint64_t n = 0;
    for (const auto& p : parts) n += p.size();
    return n;
  }
};

template <typename T>
std::span<const char> raw(std::span<const T> values) {
  return {reinterpret_cast<const char*>(values.data()), values.size_bytes()};
}

template <typename T>
std::span<const char> raw(const std::vector<T>& values) {
  return raw(std::span<const T>(values));
}

size_t value_count(const VtuArray& a) {
  return std::visit([](const auto& s) { return s.size(); }, a.values);
}

void check_arrays(const std::string& path, const std::vector<VtuArray>& arrays, size_t count,
                  const char* what) {
  std::set<std::string> names;
  for (const VtuArray& a : arrays) {
    std::string label = std::string(what) + " array '" + a.name + "'";
    if (a.name.empty()) throw MeshError(path, 0, std::string(what) + " array with an empty name");
    if (!names.insert(a.name).second) throw MeshError(path, 0, label + " appears twice");
    if (a.components < 1) throw MeshError(path, 0, label + " has fewer than 1 component");
    size_t expected = count * static_cast<size_t>(a.components);
    if (value_count(a) != expected)
      throw MeshError(path, 0,
                      label + ": expected " + std::to_string(expected) + " values (" +
                          std::to_string(count) + " x " + std::to_string(a.components) + "), got " +
                          std::to_string(value_count(a)));
  }
}

Block data_block(const VtuArray& a) {
  bool is_float = std::holds_alternative<std::span<const double>>(a.values);
  Block b;
  b.attributes = std::string("type=\"") + (is_float ? "Float64" : "Int32") + "\" Name=\"" +
                 xml_escape(a.name) + "\" NumberOfComponents=\"" + std::to_string(a.components) +
                 "\"";
  b.parts.push_back(std::visit([](const auto& s) { return raw(s); }, a.values));
  return b;
}

// The generated cell arrays, kept alive while the blocks that view them are written.
struct CellArrays {
  std::vector<int64_t> offsets;
  std::vector<uint8_t> types;
};

CellArrays cell_arrays(const Mesh& mesh) {
  CellArrays c;
  int64_t end = 0;
  auto add = [&](size_t n, int corners, uint8_t type) {
    for (size_t i = 0; i < n; ++i) {
      c.offsets.push_back(end += corners);
      c.types.push_back(type);
    }
  };
  add(mesh.tets.size(), 4, kVtkTetra);
  add(mesh.triangles.size(), 3, kVtkTriangle);
  add(mesh.edges.size(), 2, kVtkLine);
  return c;
}

std::vector<Block> geometry_blocks(const Mesh& mesh, const CellArrays& cells) {
  Block points{"type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"", {raw(mesh.points)}};
  Block connectivity{"type=\"Int32\" Name=\"connectivity\"",
                     {raw(mesh.tets), raw(mesh.triangles), raw(mesh.edges)}};
  Block offsets{"type=\"Int64\" Name=\"offsets\"", {raw(cells.offsets)}};
  Block types{"type=\"UInt8\" Name=\"types\"", {raw(cells.types)}};
  return {points, connectivity, offsets, types};
}

void append_section(std::ostringstream& xml, const char* tag, const std::vector<Block>& blocks,
                    size_t first, size_t count, uint64_t& offset) {
  xml << "      <" << tag << ">\n";
  for (size_t i = first; i < first + count; ++i) {
    xml << "        <DataArray " << blocks[i].attributes << " format=\"appended\" offset=\""
        << offset << "\"/>\n";
    offset += sizeof(uint64_t) + blocks[i].bytes();
  }
  xml << "      </" << tag << ">\n";
}

size_t cell_count(const Mesh& mesh) {
  return mesh.tets.size() + mesh.triangles.size() + mesh.edges.size();
}

// Everything up to the first appended byte; `blocks` holds the point-data arrays, the
// cell-data arrays, then the geometry blocks.
std::string vtu_header(const Mesh& mesh, const std::vector<Block>& blocks, size_t point_arrays,
                       size_t cell_arrays) {
  std::ostringstream xml;
  const char* order = std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"" << order
      << "\" header_type=\"UInt64\">\n"
      << "  <UnstructuredGrid>\n"
      << "    <Piece NumberOfPoints=\"" << mesh.points.size() << "\" NumberOfCells=\""
      << cell_count(mesh) << "\">\n";
  uint64_t offset = 0;
  size_t geometry = point_arrays + cell_arrays;
  append_section(xml, "PointData", blocks, 0, point_arrays, offset);
  append_section(xml, "CellData", blocks, point_arrays, cell_arrays, offset);
  append_section(xml, "Points", blocks, geometry, 1, offset);
  append_section(xml, "Cells", blocks, geometry + 1, 3, offset);
  xml << "    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";
  return std::move(xml).str();
}

}  // namespace

std::string xml_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

void write_vtu(const std::string& path, const Mesh& mesh, const std::vector<VtuArray>& point_data,
               const std::vector<VtuArray>& cell_data) {
  try {
    check_indices(mesh);
  } catch (const MeshError& e) {
    throw MeshError(path, 0, e.what());
  }
  check_arrays(path, point_data, mesh.points.size(), "point-data");
  check_arrays(path, cell_data, cell_count(mesh), "cell-data");

  std::vector<Block> blocks;
  for (const VtuArray& a : point_data) blocks.push_back(data_block(a));
  for (const VtuArray& a : cell_data) blocks.push_back(data_block(a));
  CellArrays cells = cell_arrays(mesh);
  for (Block& b : geometry_blocks(mesh, cells)) blocks.push_back(std::move(b));

  AtomicFile out(path);
  out.write(vtu_header(mesh, blocks, point_data.size(), cell_data.size()));
  for (const Block& b : blocks) {
    uint64_t bytes = b.bytes();
    out.write(&bytes, sizeof bytes);
    for (const auto& p : b.parts) out.write(p.data(), p.size());
  }
  out.write("\n  </AppendedData>\n</VTKFile>\n");
  out.commit();
}

void write_pvtu(const std::string& path, const std::vector<std::string>& pieces,
                const std::vector<VtuArray>& point_data, const std::vector<VtuArray>& cell_data) {
  auto declare = [](std::ostringstream& xml, const VtuArray& a) {
    const bool is_float = std::holds_alternative<std::span<const double>>(a.values);
    xml << "      <PDataArray type=\"" << (is_float ? "Float64" : "Int32") << "\" Name=\""
        << xml_escape(a.name) << "\" NumberOfComponents=\"" << a.components << "\"/>\n";
  };
  const char* order = std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"PUnstructuredGrid\" version=\"0.1\" byte_order=\"" << order
      << "\" header_type=\"UInt64\">\n"
      << "  <PUnstructuredGrid GhostLevel=\"0\">\n"
      << "    <PPoints>\n"
      << "      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n"
      << "    </PPoints>\n";
  xml << "    <PPointData>\n";
  for (const VtuArray& a : point_data) declare(xml, a);
  xml << "    </PPointData>\n    <PCellData>\n";
  for (const VtuArray& a : cell_data) declare(xml, a);
  xml << "    </PCellData>\n";
  for (const std::string& piece : pieces)
    xml << "    <Piece Source=\"" << xml_escape(piece) << "\"/>\n";
  xml << "  </PUnstructuredGrid>\n</VTKFile>\n";
  AtomicFile out(path);
  out.write(xml.str());
  out.commit();
}

}  // namespace simit::runtime
