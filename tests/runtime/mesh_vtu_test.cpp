// The .vtu and .pvd writers: the XML header is parsed back and every appended binary block is
// checked for its size and values; failures leave no file behind.
#include "runtime/mesh/vtu_writer.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <regex>

#include "mesh_test_util.h"
#include "runtime/mesh/pvd_writer.h"

namespace simit::runtime {
namespace {

using testing::mesh_error;
using testing::ScratchDir;

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A .vtu file taken apart: each DataArray's attributes and the bytes of its appended block.
struct ParsedVtu {
  std::string header;
  std::map<std::string, std::map<std::string, std::string>> arrays;  // by Name
  std::map<std::string, std::string> blocks;                         // by Name
};

ParsedVtu parse_vtu(const std::string& path) {
  std::string text = slurp(path);
  ParsedVtu vtu;
  const std::string open = "<AppendedData encoding=\"raw\">\n   _";
  size_t at = text.find(open);
  EXPECT_NE(at, std::string::npos);
  if (at == std::string::npos) return vtu;
  vtu.header = text.substr(0, at);
  size_t base = at + open.size();
  uint64_t end = base;
  std::regex tag("<DataArray ([^>]*)/>"), attr("(\\w+)=\"([^\"]*)\"");
  for (std::sregex_iterator t(vtu.header.begin(), vtu.header.end(), tag), e; t != e; ++t) {
    std::map<std::string, std::string> attrs;
    std::string body = (*t)[1];
    for (std::sregex_iterator a(body.begin(), body.end(), attr); a != e; ++a)
      attrs[(*a)[1]] = (*a)[2];
    EXPECT_EQ(attrs["format"], "appended");
    uint64_t offset = std::stoull(attrs["offset"]), bytes = 0;
    EXPECT_EQ(base + offset, end) << "blocks are contiguous, in header order";
    std::memcpy(&bytes, text.data() + base + offset, sizeof bytes);
    vtu.blocks[attrs["Name"]] = text.substr(base + offset + 8, bytes);
    end = base + offset + 8 + bytes;
    vtu.arrays[attrs["Name"]] = attrs;
  }
  EXPECT_EQ(text.substr(end), "\n  </AppendedData>\n</VTKFile>\n");
  return vtu;
}

template <typename T>
std::vector<T> values(const std::string& block) {
  EXPECT_EQ(block.size() % sizeof(T), 0u);
  std::vector<T> out(block.size() / sizeof(T));
  std::memcpy(out.data(), block.data(), block.size());
  return out;
}

Mesh pyramid_with_extras() {
  return {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 1}, {0.25, 0.25, -1}},
          {{0, 1, 2, 3}, {0, 2, 1, 4}},
          {{0, 1, 3}},
          {{0, 1}}};
}

TEST(MeshVtu, BlocksHoldTheMeshAndFields) {
  ScratchDir dir;
  Mesh m = pyramid_with_extras();
  std::vector<double> velocity(15);
  for (size_t i = 0; i < velocity.size(); ++i) velocity[i] = 0.5 * i - 1;
  std::vector<int32_t> pinned{1, 0, 0, 1, -7};
  std::vector<double> volume{1.0 / 24, 1.0 / 24, 0.1, 0.2};
  std::vector<int32_t> group{3, 4, 5, 6};
  std::string path = dir.path("f.vtu");
  write_vtu(path, m,
            {{"velocity", 3, std::span<const double>(velocity)},
             {"pinned", 1, std::span<const int32_t>(pinned)}},
            {{"volume", 1, std::span<const double>(volume)},
             {"group", 1, std::span<const int32_t>(group)}});
  EXPECT_EQ(dir.files(), std::vector<std::string>{"f.vtu"});

  ParsedVtu vtu = parse_vtu(path);
  EXPECT_NE(vtu.header.find("<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
                            "byte_order=\"LittleEndian\" header_type=\"UInt64\">"),
            std::string::npos);
  EXPECT_NE(vtu.header.find("<Piece NumberOfPoints=\"5\" NumberOfCells=\"4\">"), std::string::npos);
  EXPECT_LT(vtu.header.find("Name=\"pinned\""), vtu.header.find("<CellData>"));
  EXPECT_GT(vtu.header.find("Name=\"group\""), vtu.header.find("<CellData>"));
  EXPECT_EQ(vtu.arrays["velocity"]["type"], "Float64");
  EXPECT_EQ(vtu.arrays["velocity"]["NumberOfComponents"], "3");
  EXPECT_EQ(vtu.arrays["pinned"]["type"], "Int32");
  EXPECT_EQ(vtu.arrays["connectivity"]["type"], "Int32");
  EXPECT_EQ(vtu.arrays["offsets"]["type"], "Int64");
  EXPECT_EQ(vtu.arrays["types"]["type"], "UInt8");

  EXPECT_EQ(values<double>(vtu.blocks["velocity"]), velocity);
  EXPECT_EQ(values<int32_t>(vtu.blocks["pinned"]), pinned);
  EXPECT_EQ(values<double>(vtu.blocks["volume"]), volume);
  EXPECT_EQ(values<int32_t>(vtu.blocks["group"]), group);
  EXPECT_EQ(values<double>(vtu.blocks["Points"]),
            (std::vector<double>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0.25, 0.25, 1, 0.25, 0.25, -1}));
  EXPECT_EQ(values<int32_t>(vtu.blocks["connectivity"]),
            (std::vector<int32_t>{0, 1, 2, 3, 0, 2, 1, 4, 0, 1, 3, 0, 1}));
  EXPECT_EQ(values<int64_t>(vtu.blocks["offsets"]), (std::vector<int64_t>{4, 8, 11, 13}));
  EXPECT_EQ(values<uint8_t>(vtu.blocks["types"]), (std::vector<uint8_t>{10, 10, 5, 3}));
}

TEST(MeshVtu, NamesAreEscapedAndEmptyMeshesWritten) {
  ScratchDir dir;
  std::string path = dir.path("e.vtu");
  std::vector<double> none;
  write_vtu(path, Mesh{}, {{"a<b&\"c\"", 3, std::span<const double>(none)}}, {});
  ParsedVtu vtu = parse_vtu(path);
  EXPECT_NE(vtu.header.find("Name=\"a&lt;b&amp;&quot;c&quot;\""), std::string::npos);
  EXPECT_NE(vtu.header.find("NumberOfPoints=\"0\" NumberOfCells=\"0\""), std::string::npos);
  EXPECT_EQ(vtu.blocks["Points"].size(), 0u);
}

TEST(MeshVtu, BadInputWritesNothing) {
  ScratchDir dir;
  std::string path = dir.path("bad.vtu");
  Mesh m = pyramid_with_extras();
  std::vector<double> short_field(12), cells(4);
  EXPECT_EQ(mesh_error([&] {
              write_vtu(path, m, {{"v", 3, std::span<const double>(short_field)}}, {});
            }),
            path + ": point-data array 'v': expected 15 values (5 x 3), got 12");
  EXPECT_EQ(mesh_error([&] {
              write_vtu(path, m, {},
                        {{"c", 1, std::span<const double>(cells)},
                         {"c", 1, std::span<const double>(cells)}});
            }),
            path + ": cell-data array 'c' appears twice");
  EXPECT_EQ(mesh_error([&] {
              write_vtu(path, m, {}, {{"", 1, std::span<const double>(cells)}});
            }),
            path + ": cell-data array with an empty name");
  m.tets[1][3] = 5;
  EXPECT_EQ(mesh_error([&] { write_vtu(path, m, {}, {}); }),
            path + ": tet 1: vertex index 5 is beyond the vertex count 5");
  EXPECT_TRUE(dir.files().empty());
  EXPECT_EQ(mesh_error([&] {
              write_vtu(dir.path("no/such/dir/x.vtu"), Mesh{}, {}, {});
            }).rfind(dir.path("no/such/dir/x.vtu") + ": cannot create a temporary file", 0),
            0u);
}

TEST(MeshVtu, RewritingReplacesTheFileWhole) {
  ScratchDir dir;
  std::string path = dir.path("r.vtu");
  Mesh m = pyramid_with_extras();
  write_vtu(path, m, {}, {});
  m.points[0] = {9, 9, 9};
  write_vtu(path, m, {}, {});
  EXPECT_EQ(dir.files(), std::vector<std::string>{"r.vtu"});
  EXPECT_EQ(values<double>(parse_vtu(path).blocks["Points"])[0], 9.0);
}

TEST(MeshPvd, CollectionIsRewrittenAfterEachFrame) {
  ScratchDir dir;
  PvdWriter pvd(dir.path("run.pvd"));
  Mesh m = pyramid_with_extras();
  std::vector<double> x(15);
  const double times[] = {0, 0.005, 0.01};
  for (int frame = 0; frame < 3; ++frame) {
    x[0] = frame;
    std::string vtu = pvd.write_frame(times[frame], m, {{"x", 3, std::span<const double>(x)}}, {});
    EXPECT_EQ(vtu, dir.path("run_00000" + std::to_string(frame) + ".vtu"));
    EXPECT_EQ(values<double>(parse_vtu(vtu).blocks["x"])[0], frame);
    std::string collection = slurp(dir.path("run.pvd"));
    std::regex entry("<DataSet timestep=\"([^\"]*)\" group=\"\" part=\"0\" file=\"([^\"]*)\"/>");
    std::vector<std::string> listed;
    for (std::sregex_iterator i(collection.begin(), collection.end(), entry), e; i != e; ++i)
      listed.push_back((*i)[1].str() + " " + (*i)[2].str());
    ASSERT_EQ(listed.size(), static_cast<size_t>(frame + 1));
    EXPECT_EQ(listed.back(), (std::vector<std::string>{"0 run_000000.vtu", "0.005 run_000001.vtu",
                                                       "0.01 run_000002.vtu"}[frame]));
    EXPECT_NE(collection.find("<VTKFile type=\"Collection\""), std::string::npos);
  }
  EXPECT_EQ(pvd.frames(), 3u);
  EXPECT_EQ(dir.files(), (std::vector<std::string>{"run.pvd", "run_000000.vtu", "run_000001.vtu",
                                                   "run_000002.vtu"}));
}

}  // namespace
}  // namespace simit::runtime
