// Bad scenes given to `simit run`: each mistake exits 1 with one message naming the scene's
// line and column (or the mesh file's line), before any frame runs and without creating the
// output folder. Also the quick-look picture: [output] png and --png.
#include "cli.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace simit::tools {
namespace {

namespace fs = std::filesystem;

// One tet in TetGen's orientation (det[x0-x3 | x1-x3 | x2-x3] = -1).
const char* kNode = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
const char* kEle = "1 4 0\n0 0 1 2 3\n";

class SceneErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "simit-scene-errors-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    write("tet.node", kNode);
    write("tet.ele", kEle);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
  }

  // The fem example on one tet, writing into out/.
  std::string fem_scene() const {
    return "program = \"" + std::string(SIMIT_SOURCE_DIR) +
           "/examples/fem/fem.sim\"\n"
           "init = \"init\"\n"
           "step = \"step\"\n"
           "frames = 1\n"
           "[tensors]\n"
           "cg_tol = 1e-12\n"
           "cg_max = 10\n"
           "[sets.verts]\n"
           "mesh = \"tet.node\"\n"
           "elements = \"vertices\"\n"
           "[sets.verts.fields]\n"
           "x = \"position\"\n"
           "[sets.tets]\n"
           "mesh = \"tet.node\"\n"
           "elements = \"tets\"\n"
           "[output]\n"
           "folder = \"" +
           path("out") +
           "\"\n"
           "name = \"tet\"\n"
           "points = \"verts\"\n"
           "position = \"x\"\n"
           "cells = \"tets\"\n";
  }

  // The cloth example on a generated 4 x 4 square, writing into out/.
  std::string cloth_scene() const {
    std::string s = "program = \"" + std::string(SIMIT_SOURCE_DIR) +
                    "/examples/cloth/cloth.sim\"\n"
                    "init = \"init\"\n"
                    "step = \"step\"\n"
                    "frames = 1\n";
    for (const char* set : {"points", "faces", "hinges"}) {
      s += std::string("[sets.") + set + "]\ngenerate = \"square_cloth\"\nn = 4\nelements = \"" +
           (std::string(set) == "points"  ? "vertices"
            : std::string(set) == "faces" ? "triangles"
                                          : "hinges") +
           "\"\n";
    }
    s += "[sets.points.fields]\nx = \"position\"\n[output]\nfolder = \"" + path("out") +
         "\"\nname = \"cloth\"\npoints = \"points\"\nposition = \"x\"\ncells = \"faces\"\n";
    return s;
  }

  struct Result {
    int status;
    std::string out, err;
  };
  Result run(const std::string& scene, std::vector<std::string> extra = {}) const {
    write("scene.toml", scene);
    std::vector<std::string> args = {"simit", "run", path("scene.toml")};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<const char*> argv;
    for (const std::string& a : args) argv.push_back(a.c_str());
    std::ostringstream out, err;
    int status = run_cli(static_cast<int>(argv.size()), argv.data(), out, err);
    return {status, out.str(), err.str()};
  }

  // "DIR/scene.toml:LINE:COL: error: " where `marker` starts in `scene` (1-based, as toml++).
  std::string location(const std::string& scene, const std::string& marker) const {
    size_t at = scene.find(marker);
    EXPECT_NE(at, std::string::npos) << marker;
    if (at == std::string::npos) return "?";
    const size_t line_start =
        scene.rfind('\n', at) == std::string::npos ? 0 : scene.rfind('\n', at) + 1;
    const int line = 1 + static_cast<int>(std::count(scene.begin(), scene.begin() + at, '\n'));
    const int col = 1 + static_cast<int>(at - line_start);
    return path("scene.toml") + ":" + std::to_string(line) + ":" + std::to_string(col) +
           ": error: ";
  }

  // Runs `scene`, which must fail at `marker` with a message containing `what`, write nothing
  // to stdout about frames, and leave no output folder.
  void expect_error(const std::string& scene, const std::string& marker, const std::string& what,
                    std::vector<std::string> extra = {}) {
    Result r = run(scene, extra);
    EXPECT_EQ(r.status, 1) << r.err;
    if (!marker.empty()) {
      EXPECT_EQ(r.err.rfind(location(scene, marker), 0), 0u) << r.err;
    }
    EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("frame 1/"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(path("out"))) << "the output folder was created: " << r.err;
  }

  static std::string replace(std::string s, const std::string& from, const std::string& to) {
    size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) s.replace(at, from.size(), to);
    return s;
  }

  fs::path dir_;
};

TEST_F(SceneErrors, TheGoodScenesRun) {
  Result fem = run(fem_scene());
  EXPECT_EQ(fem.status, 0) << fem.err;
  EXPECT_TRUE(fs::exists(path("out/tet.pvd")));
  fs::remove_all(path("out"));
  Result cloth = run(cloth_scene());
  EXPECT_EQ(cloth.status, 0) << cloth.err;
  EXPECT_TRUE(fs::exists(path("out/cloth.pvd")));
}

TEST_F(SceneErrors, Tensors) {
  const std::string s = fem_scene();
  std::string bad = replace(s, "cg_max = 10\n", "cg_max = 10\ncg_tolerance = 1e-6\n");
  expect_error(bad, "1e-6",
               "[tensors] cg_tolerance: the program declares no extern tensor 'cg_tolerance' "
               "(its extern tensors: cg_max, cg_tol)");
  bad = replace(s, "cg_max = 10", "cg_max = 10.5");
  expect_error(bad, "10.5", "[tensors] cg_max: extern 'cg_max' is int: expected a whole number");
  // TOML's integers are 64-bit; Simit's int is not (these used to wrap silently).
  bad = replace(s, "cg_max = 10", "cg_max = 4294967306");
  expect_error(bad, "4294967306",
               "[tensors] cg_max: extern 'cg_max' is int: expected a whole number from "
               "-2147483648 to 2147483647");
  bad = replace(s, "cg_max = 10", "cg_max = -2147483649");
  expect_error(bad, "-2147483649", "expected a whole number from -2147483648 to 2147483647");
  bad = replace(s, "cg_tol = 1e-12", "cg_tol = true");
  expect_error(bad, "true", "extern 'cg_tol' is float: expected a number");
  bad = replace(s, "cg_tol = 1e-12", "cg_tol = [1e-12, 1e-10]");
  expect_error(bad, "[1e-12", "extern 'cg_tol' is float with 1 component, but 2 values were given");
  bad = replace(s, "cg_max = 10\n", "");
  expect_error(bad, "\"step\"",
               "step: 'step' uses the extern tensor 'cg_max' (int), which is not set: add it to "
               "[tensors]");
  bad = replace(s, "[tensors]\ncg_tol = 1e-12\ncg_max = 10\n", "tensors = 3\n");
  expect_error(bad, "3\n", "tensors: expected a table");
}

TEST_F(SceneErrors, Generate) {
  const std::string s = cloth_scene();
  std::string bad = replace(s, "generate = \"square_cloth\"", "generate = \"sphere\"");
  expect_error(bad, "\"sphere\"",
               "[sets.points] generate: 'sphere' is not a generator (expected square_cloth)");
  bad = replace(s, "generate = \"square_cloth\"\nn = 4\n", "generate = \"square_cloth\"\n");
  expect_error(bad, "\"square_cloth\"",
               "[sets.points]: generate = \"square_cloth\" needs n (points per side)");
  bad = replace(s, "n = 4", "n = 1");
  expect_error(bad, "1\nelements", "[sets.points] n: expected a whole number from 2 to 4096");
  bad = replace(s, "n = 4", "n = \"4\"");
  expect_error(bad, "\"4\"", "[sets.points] n: expected a whole number from 2 to 4096");
  bad =
      replace(s, "generate = \"square_cloth\"", "generate = \"square_cloth\"\nmesh = \"tet.node\"");
  expect_error(bad, "\"square_cloth\"", "[sets.points]: give either mesh or generate, not both");
  bad = replace(fem_scene(), "mesh = \"tet.node\"", "mesh = \"tet.node\"\nn = 3");
  expect_error(bad, "3\nelements", "[sets.verts] n: only for generate");
}

// `frames` is an int, as --frames is: 2^32 + 1 frames must not run one.
TEST_F(SceneErrors, FramesInRange) {
  const std::string s = fem_scene();
  expect_error(replace(s, "frames = 1", "frames = 4294967297"), "4294967297",
               "frames: expected a whole number from 0 to 2147483647");
  expect_error(replace(s, "frames = 1", "frames = -1"), "-1",
               "frames: expected a whole number from 0 to 2147483647");
  expect_error(replace(s, "frames = 1", "frames = 1.5"), "1.5",
               "frames: expected a whole number from 0 to 2147483647");
}

TEST_F(SceneErrors, KeysSetsAndFields) {
  const std::string s = fem_scene();
  expect_error(replace(s, "frames = 1", "frames = 1\nframe = 2"), "2\n",
               "unknown key 'frame' in the scene (expected one of: ");
  expect_error(replace(s, "cells = \"tets\"", "cells = \"tets\"\npng_file = \"a.png\""),
               "\"a.png\"", "unknown key 'png_file' in [output]");
  expect_error(replace(s, "x = \"position\"", "x = \"position\"\nq = 1.0"), "1.0",
               "[sets.verts.fields] q: element Vertex (of extern 'verts') declares no field 'q' "
               "(its fields: x, v, m, pinned)");
  expect_error(replace(s, "x = \"position\"", "v = [1.0, 2.0]"), "[1.0",
               "field 'v' (float 3) has 3 components per element, but 2 values were "
               "given");
  expect_error(replace(s, "x = \"position\"", "pinned = \"y <\""), "\"y <\"",
               "[sets.verts.fields] pinned: in \"y <\": ");
  expect_error(replace(s, "[sets.tets]",
                       "[sets.springs]\nmesh = \"tet.node\"\nelements = \"edges\"\n[sets.tets]"),
               "", "[sets.springs]: the program declares no extern set 'springs'");
}

TEST_F(SceneErrors, Meshes) {
  const std::string s = fem_scene();
  const std::string at = "\"tet.node\"\nelements = \"vertices\"";
  write("tet.ele", "1 4 0\n0 0 1 2 4\n");
  expect_error(s, at, path("tet.ele") + ":2: expected a vertex index in [0, 4), got '4'");
  write("tet.ele", "1 4 0\n0 0 1 2 2\n");
  expect_error(s, at, "tet 0 (vertices 0 1 2 2) has zero volume");
  write("tet.ele", "1 4 0\n0 0 1 2 3\n");
  write("tet.node", "4 3 0 0\n0 0 0 0\n1 1 zero 0\n2 0 1 0\n3 0 0 1\n");
  expect_error(s, at, path("tet.node") + ":3: expected ");
  write("tet.node", kNode);
  expect_error(replace(s, "mesh = \"tet.node\"", "mesh = \"none.node\""), "\"none.node\"",
               "[sets.verts] mesh: no such file '" + path("none.node") + "'");
  // A 1-based mesh: the degenerate tet and its vertices in the file's own numbering.
  write("tet.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n");
  write("tet.ele", "1 4 0\n7 1 2 3 3\n");
  expect_error(s, at,
               path("tet.node") + ": tet 7 (vertices 1 2 3 3) has zero volume (relative size 0)\n");
  write("tet.node", kNode);
  // No .ele file: the message names it rather than saying only that there are no tets.
  fs::remove(path("tet.ele"));
  expect_error(s, "\"tets\"\n[output]",
               "[sets.tets]: the mesh '" + path("tet.node") + "' gives no tets: they come from '" +
                   path("tet.ele") + "', which does not exist\n");
}

TEST_F(SceneErrors, QuickLookPicture) {
  const std::string s = fem_scene();
  expect_error(s + "png = \"tet.jpg\"\n", "\"tet.jpg\"",
               "[output] png: '" + path("out/tet.jpg") + "' is not a .png file name");
  expect_error(s + "png = \"pics/tet.png\"\n", "\"pics/tet.png\"",
               "[output] png: the folder '" + path("out/pics") + "' does not exist");
  expect_error(s, "", "--png: the folder '" + path("nowhere") + "' does not exist",
               {"--png", path("nowhere/tet.png")});
  // The picture is written (a PNG signature), with no temporary file beside it.
  Result r = run(s + "png = \"tet.png\"\n");
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream png(path("out/tet.png"), std::ios::binary);
  char signature[8] = {};
  png.read(signature, 8);
  EXPECT_EQ(std::string(signature, 8), "\x89PNG\r\n\x1a\n");
  for (const auto& entry : fs::directory_iterator(path("out")))
    EXPECT_EQ(entry.path().filename().string().find(".png."), std::string::npos) << entry.path();
  // --png overrides it, relative to the current folder (here an absolute path).
  r = run(s + "png = \"tet.png\"\n", {"--png", path("other.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(path("other.png")));
}

}  // namespace
}  // namespace simit::tools
