// Scenes renumber their meshes for locality (the `reorder` key) and still show the mesh's own
// numbering: on a cube of tets listed in a shuffled order, the sets are built renumbered with
// their mesh numbers and field values, a reordered run writes the same frames and final
// positions as one that keeps the file's order, and errors name the mesh's elements.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "scene/mesh_binding.h"
#include "scene/mesh_cache.h"
#include "scene/scene_file.h"
#include "scene/scene_sets.h"
#include "simit/scene.h"

namespace simit::scene {
namespace {

namespace fs = std::filesystem;
using Vec = std::array<double, 3>;

// An n x n x n cube of unit cells scaled by `h`, each cell split into six tets along its main
// diagonal (Kuhn), vertices and tets both listed in a shuffled order, every tet in TetGen's
// orientation (det[x0-x3 | x1-x3 | x2-x3] < 0) so that reading keeps it as written.
struct ShuffledCube {
  std::vector<Vec> points;
  std::vector<std::array<int, 4>> tets;

  ShuffledCube(int n, double h, unsigned seed) {
    const int side = n + 1;
    auto at = [&](int i, int j, int k) { return i + side * (j + side * k); };
    std::vector<int> label(static_cast<size_t>(side * side * side));
    std::iota(label.begin(), label.end(), 0);
    std::mt19937 rng(seed);
    std::shuffle(label.begin(), label.end(), rng);
    points.resize(label.size());
    for (int k = 0; k < side; ++k)
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) points[label[at(i, j, k)]] = {h * i, h * j, h * k};
    const int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
          for (const auto& a : axes) {
            std::array<int, 3> c = {i, j, k};
            std::array<int, 4> t;
            t[0] = label[at(c[0], c[1], c[2])];
            ++c[a[0]];
            t[1] = label[at(c[0], c[1], c[2])];
            ++c[a[1]];
            t[2] = label[at(c[0], c[1], c[2])];
            t[3] = label[at(i + 1, j + 1, k + 1)];
            if (det(t) > 0) std::swap(t[0], t[1]);
            tets.push_back(t);
          }
    std::shuffle(tets.begin(), tets.end(), rng);
  }

  double det(const std::array<int, 4>& t) const {
    Vec d[3];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) d[r][c] = points[t[r]][c] - points[t[3]][c];
    return d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1]) -
           d[1][0] * (d[0][1] * d[2][2] - d[0][2] * d[2][1]) +
           d[2][0] * (d[0][1] * d[1][2] - d[0][2] * d[1][1]);
  }

  Vec centroid(int tet) const {
    Vec c = {0, 0, 0};
    for (int v : tets[tet])
      for (int d = 0; d < 3; ++d) c[d] += 0.25 * points[v][d];
    return c;
  }

  void write(const fs::path& base) const {
    std::ofstream node(base.string() + ".node");
    node.precision(17);
    node << points.size() << " 3 0 0\n";
    for (size_t i = 0; i < points.size(); ++i)
      node << i << ' ' << points[i][0] << ' ' << points[i][1] << ' ' << points[i][2] << '\n';
    std::ofstream ele(base.string() + ".ele");
    ele << tets.size() << " 4 0\n";
    for (size_t i = 0; i < tets.size(); ++i)
      ele << i << ' ' << tets[i][0] << ' ' << tets[i][1] << ' ' << tets[i][2] << ' ' << tets[i][3]
          << '\n';
  }
};

constexpr int kCells = 4;
constexpr double kCell = 0.025;  // a 0.1 m cube, as tests/data/bar2k

// examples/fem/fem.sim on the cube with CG run to convergence (r'r <= 1e-24), so that the
// positions depend on the order of the sums only in their last bits.
std::string fem_scene(const std::string& reorder) {
  return "program = \"" SIMIT_SOURCE_DIR "/examples/fem/fem.sim\"\n" + reorder +
         "init = \"init\"\nstep = \"step\"\nframes = 3\nframe_time = 0.005\n"
         "[tensors]\ncg_tol = 1e-24\ncg_max = 10000\n"
         "[sets.verts]\nmesh = \"cube.node\"\nelements = \"vertices\"\n"
         "[sets.verts.fields]\nx = \"position\"\nv = [0.1, 0.0, 0.1]\npinned = \"y < 1e-4\"\n"
         "[sets.tets]\nmesh = \"cube.node\"\nelements = \"tets\"\n"
         "[output]\nfolder = \"out\"\nname = \"cube\"\npoints = \"verts\"\nposition = \"x\"\n"
         "cells = \"tets\"\npoint_fields = [\"v\", \"pinned\"]\ncell_fields = [\"W\"]\n";
}

// A map over the tets whose function fails at the tet marked `bad`: "error", an `error`
// statement (line 13); "field", a NaN written to a field of the tet, which --check-finite or
// the frame's finite check stops (a compiled map that writes fields reports its error itself,
// jit/site_kernel.cpp; one that does not runs again interpreted); "sum", a NaN summed into its
// vertices only.
std::string failing_program(const std::string& kind) {
  std::string head =
      kind == "field" ? "func spread(inout t : Tet, v : (Vertex * 4)) -> s : vector[verts](float)\n"
                        "  t.r = sqrt(0.5 - t.bad);\n"
                      : "func spread(t : Tet, v : (Vertex * 4)) -> s : vector[verts](float)\n";
  if (kind == "error") head += "  if t.bad > 0.5\n    error \"a bad tet\";\n  end\n";
  return "element Vertex\n  x : vector[3](float);\n  s : float;\nend\n"
         "element Tet\n  bad : float;\n  r : float;\nend\n"
         "extern verts : set{Vertex};\n"
         "extern tets : set{Tet}(verts, verts, verts, verts);\n" +
         head +
         "  for j in 0:4\n    s(v(j)) = sqrt(0.5 - t.bad);\n  end\n"
         "end\nexport func step()\n  verts.s = map spread to tets reduce +;\nend\n";
}

class SceneReorderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "simit-reorder-test-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    cube_.write(dir_ / "cube");
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
  }
  static std::string read(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  // Runs `scene` into out_NAME (with an [output], the final positions in NAME.csv); the error
  // text on failure.
  std::string run(const std::string& scene, const std::string& name, bool jit = false,
                  bool check_finite = false) {
    SceneOptions o;
    o.file = path(scene);
    o.output_dir = path("out_" + name);
    if (read(path(scene)).find("[output]") != std::string::npos) o.final_csv = path(name + ".csv");
    o.check_finite = check_finite;
    if (jit) {
      o.executor.kind = ExecutorKind::Jit;
      o.executor.threshold = 0;  // every site compiled at its first execution
      o.executor.threads = 2;
      o.executor.jit_cache = "off";
      o.executor_given = true;
    }
    std::ostringstream out, err;
    const int status = run_scene(o, out, err);
    return status == 0 ? "" : err.str() + "(exit " + std::to_string(status) + ")";
  }
  // The tet whose centroid is `c` (within rounding), by its index in the file.
  int tet_at(const Vec& c) const {
    for (size_t t = 0; t < cube_.tets.size(); ++t) {
      const Vec m = cube_.centroid(static_cast<int>(t));
      if (std::abs(m[0] - c[0]) + std::abs(m[1] - c[1]) + std::abs(m[2] - c[2]) < 1e-9)
        return static_cast<int>(t);
    }
    return -1;
  }

  const ShuffledCube cube_{kCells, kCell, 2024};
  fs::path dir_;
};

std::vector<std::vector<double>> csv_rows(const std::string& file) {
  std::ifstream in(file);
  std::vector<std::vector<double>> rows;
  std::string line;
  std::getline(in, line);  // x,y,z
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream s(line);
    for (std::string v; std::getline(s, v, ',');) row.push_back(std::stod(v));
    rows.push_back(row);
  }
  return rows;
}

// The raw bytes of the .vtu's cell arrays (connectivity, offsets, types): from the
// connectivity's offset in the appended data to the end of the file.
std::string cell_bytes(const std::string& vtu) {
  const size_t name = vtu.find("Name=\"connectivity\"");
  const size_t offset = vtu.find("offset=\"", name);
  if (name == std::string::npos || offset == std::string::npos) return "";
  const size_t start = vtu.find('_', vtu.find("<AppendedData")) + 1;
  return vtu.substr(start + std::stoull(vtu.substr(offset + 8)));
}

TEST_F(SceneReorderTest, TheSetsAreRenumberedWithTheirMeshNumbersAndFieldValues) {
  write("fem.toml", fem_scene(""));
  const std::unique_ptr<SceneFile> file = read_scene_file(path("fem.toml"));
  EXPECT_EQ(file->reorder, Reorder::Rcm);  // the default
  MeshCache meshes;
  const BoundSets sets = build_sets(*file, meshes, false, Reorder::Rcm);
  const runtime::Set& verts = *sets.by_name.at("verts")->set;
  const runtime::Set& tets = *sets.by_name.at("tets")->set;
  ASSERT_EQ(verts.size(), 125);
  ASSERT_EQ(tets.size(), 384);
  ASSERT_TRUE(verts.has_mesh_numbers());
  ASSERT_TRUE(tets.has_mesh_numbers());
  int moved = 0;
  for (int v = 0; v < verts.size(); ++v) {
    const int m = verts.mesh_number(v);
    moved += m != v;
    // The values given per mesh vertex (its position, an expression of it) are on the vertex.
    for (int d = 0; d < 3; ++d)
      EXPECT_EQ(verts.field("x").at<double>(v)[d], cube_.points[m][d]) << v;
    EXPECT_EQ(verts.field("pinned").at<bool>(v)[0], cube_.points[m][1] < 1e-4) << v;
  }
  EXPECT_GT(moved, 100);
  int lowest = -1;
  for (int t = 0; t < tets.size(); ++t) {
    const int m = tets.mesh_number(t);
    for (int k = 0; k < 4; ++k)  // the same vertices, in the same order, renumbered
      EXPECT_EQ(verts.mesh_number(tets.endpoint(t, k)), cube_.tets[m][k]) << t;
    // Sorted by the smallest new vertex.
    const int least = *std::min_element(tets.endpoints_of(t).begin(), tets.endpoints_of(t).end());
    EXPECT_GE(least, lowest) << t;
    lowest = least;
  }
  // Off: the file's order, no mesh numbers.
  const BoundSets off = build_sets(*file, meshes, false, Reorder::Off);
  EXPECT_FALSE(off.by_name.at("verts")->set->has_mesh_numbers());
  EXPECT_FALSE(off.by_name.at("tets")->set->has_mesh_numbers());
  // The REPL's :scene indexes its sets by element: the file's order too.
  std::ostringstream err;
  const std::optional<SceneSets> repl = load_scene_sets(path("fem.toml"), false, err);
  ASSERT_TRUE(repl) << err.str();
  for (const auto& [name, set] : repl->sets) EXPECT_FALSE(set->has_mesh_numbers()) << name;
}

TEST_F(SceneReorderTest, AReorderedRunWritesWhatTheFilesOrderWrites) {
  write("off.toml", fem_scene("reorder = false\n"));
  write("rcm.toml", fem_scene("reorder = \"rcm\"\n"));
  write("hilbert.toml", fem_scene("reorder = \"hilbert\"\n"));
  ASSERT_EQ(run("off.toml", "off"), "");
  for (const std::string name : {"rcm", "hilbert"}) {
    ASSERT_EQ(run(name + ".toml", name), "") << name;
    // Frame 0 (after init: positions, velocities, pinned vertices, rest volumes per tet) holds
    // no sum over elements: the same bytes in the same order.
    const std::string first = "/cube_000000.vtu";
    EXPECT_EQ(read(path("out_" + name) + first), read(path("out_off") + first)) << name;
    // The last frame: the same cells; the positions to the rounding of the sums' order.
    const std::string last = "/cube_000003.vtu";
    const std::string cells = cell_bytes(read(path("out_" + name) + last));
    EXPECT_FALSE(cells.empty());
    EXPECT_EQ(cells, cell_bytes(read(path("out_off") + last))) << name;
    const auto a = csv_rows(path(name + ".csv")), b = csv_rows(path("off.csv"));
    ASSERT_EQ(a.size(), 125u);
    ASSERT_EQ(b.size(), 125u);
    double scale = 0, diff = 0, moved = 0;
    for (size_t i = 0; i < a.size(); ++i)
      for (int d = 0; d < 3; ++d) {
        scale = std::max(scale, std::abs(b[i][d]));
        diff = std::max(diff, std::abs(a[i][d] - b[i][d]));
        moved = std::max(moved, std::abs(b[i][d] - cube_.points[i][d]));
      }
    EXPECT_GT(moved, 1e-4);  // the frames did move the cube
    EXPECT_LE(diff, 1e-12 * scale) << name;
  }
}

TEST_F(SceneReorderTest, ErrorsNameTheMeshsElements) {
  // The marked tet: in the corner cell, along x, then y, then z (centroid offset 3/4, 1/2,
  // 1/4 of a cell).
  const double c0 = (kCells - 1) * kCell;
  const Vec centroid = {c0 + 0.75 * kCell, c0 + 0.5 * kCell, c0 + 0.25 * kCell};
  const int bad = tet_at(centroid);
  ASSERT_GE(bad, 0);
  const std::array<int, 4>& v = cube_.tets[bad];
  const std::string note = "mapping over element " + std::to_string(bad) +
                           " of set 'tets' (endpoints " + std::to_string(v[0]) + ", " +
                           std::to_string(v[1]) + ", " + std::to_string(v[2]) + ", " +
                           std::to_string(v[3]) + " of 'verts')";
  auto scene = [&](const std::string& program) {
    std::ostringstream at;
    at.precision(17);
    at << "abs(x - " << centroid[0] << ") < 1e-6 and abs(y - " << centroid[1]
       << ") < 1e-6 and abs(z - " << centroid[2] << ") < 1e-6";
    return "program = \"" + program +
           "\"\nstep = \"step\"\nframes = 1\n"
           "[sets.verts]\nmesh = \"cube.node\"\nelements = \"vertices\"\n"
           "[sets.verts.fields]\nx = \"position\"\n"
           "[sets.tets]\nmesh = \"cube.node\"\nelements = \"tets\"\n"
           "[sets.tets.fields]\nbad = \"" +
           at.str() + "\"\n";
  };
  for (const std::string kind : {"error", "field", "sum"}) {
    write(kind + ".sim", failing_program(kind));
    write(kind + ".toml", scene(kind + ".sim"));
  }
  // The renumbering moved the marked tet: a message in the set's own numbers would differ.
  {
    const std::unique_ptr<SceneFile> file = read_scene_file(path("error.toml"));
    MeshCache meshes;
    const BoundSets sets = build_sets(*file, meshes, false, file->reorder);
    const runtime::Set& tets = *sets.by_name.at("tets")->set;
    int marked = -1;
    for (int t = 0; t < tets.size(); ++t)
      if (tets.field("bad").at<double>(t)[0] != 0) {
        EXPECT_EQ(marked, -1) << "one tet is marked";
        marked = t;
      }
    ASSERT_GE(marked, 0);
    EXPECT_EQ(tets.mesh_number(marked), bad);
    EXPECT_NE(marked, bad);
  }
  const std::vector<bool> executors =
      jit_available() ? std::vector<bool>{false, true} : std::vector<bool>{false};
  for (bool jit : executors) {
    SCOPED_TRACE(jit ? "jit" : "interpreter");
    std::string err = run("error.toml", "error", jit);
    EXPECT_NE(err.find("runtime error: a bad tet"), std::string::npos) << err;
    EXPECT_NE(err.find("in spread (" + path("error.sim") + ":13), " + note), std::string::npos)
        << err;
    // --check-finite: the NaN the marked tet makes, at its statement and element.
    err = run("field.toml", "field", jit, true);
    EXPECT_NE(err.find("field.sim:12:9: runtime error: the operation produced"), std::string::npos)
        << err;
    EXPECT_NE(err.find("in spread (" + path("field.sim") + ":12), " + note), std::string::npos)
        << err;
  }
  std::string err = run("field.toml", "finite");
  EXPECT_NE(err.find("after frame 1: field 'r' of element " + std::to_string(bad) +
                     " of set 'tets' is nan"),
            std::string::npos)
      << err;
  // The frames' finite check: the NaN reaches the marked tet's four vertices; the message
  // names the one the mesh numbers first.
  err = run("sum.toml", "finite");
  const std::string vertex = std::to_string(*std::min_element(v.begin(), v.end()));
  EXPECT_NE(err.find("after frame 1: field 's' of element " + vertex + " of set 'verts' is nan"),
            std::string::npos)
      << err;
}

TEST_F(SceneReorderTest, BadReorderValuesAreLocated) {
  write("bad.toml", fem_scene("reorder = \"metis\"\n"));
  std::ostringstream out, err;
  SceneOptions o;
  o.file = path("bad.toml");
  EXPECT_EQ(run_scene(o, out, err), 1);
  EXPECT_EQ(err.str(), path("bad.toml") +
                           ":2:11: error: reorder: expected true, false, \"rcm\" or \"hilbert\", "
                           "not \"metis\"\n");
  write("bad.toml", fem_scene("reorder = 1\n"));
  err.str("");
  EXPECT_EQ(run_scene(o, out, err), 1);
  EXPECT_EQ(err.str(), path("bad.toml") +
                           ":2:11: error: reorder: expected true, false, \"rcm\" or \"hilbert\"\n");
}

}  // namespace
}  // namespace simit::scene
