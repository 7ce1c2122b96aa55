// Bad scenes given to `simit run`: each mistake exits 1 with one message naming the scene's
// line and column (or the mesh file's line), before any frame runs and without creating the
// output folder. Also the quick-look picture: [output] png and --png.
#include "cli.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
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

// Characters outside ASCII are refused outside strings and comments (TOML allows none there;
// toml++ 3.3 would reach unreachable code on some), and are fine inside them.
TEST_F(SceneErrors, NonAsciiOutsideStringsAndComments) {
  const std::string s = fem_scene();
  expect_error(replace(s, "frames = 1", "frames = 1 \xc3\xa9"), "\xc3\xa9",
               "a character outside ASCII outside a string or comment");
  expect_error(replace(s, "frames = 1",
                       "\xc3\xa9"
                       "frames = 1"),
               "\xc3\xa9", "a character outside ASCII outside a string or comment");
  Result ok =
      run(replace(s, "frames = 1",
                  "frames = 1  # caf\xc3\xa9\n# \xe2\x82\xac\nframe_time = 0.01 # \xc3\xa9"),
          {});
  EXPECT_EQ(ok.status, 0) << ok.err;
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
               "[output] png: 'pics/tet.png' is not a plain file name (output files go directly "
               "in the output folder: no '/', no '..')");
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

// [output] name, csv and png are plain names inside the output folder, distinct from each other
// and from every input of the run; --final-csv and --png are checked against them too. Each is
// reported at its key before anything is written.
TEST_F(SceneErrors, OutputNames) {
  const std::string s = fem_scene();
  const std::string plain =
      "' is not a plain file name (output files go directly in the output folder: no '/', no "
      "'..')";
  expect_error(replace(s, "name = \"tet\"", "name = \"\""), "\"\"\npoints",
               "[output] name: expected a file name, not an empty string");
  expect_error(replace(s, "name = \"tet\"", "name = \"../tet\""), "\"../tet\"",
               "[output] name: '../tet" + plain);
  expect_error(replace(s, "name = \"tet\"", "name = \"sub/tet\""), "\"sub/tet\"",
               "[output] name: 'sub/tet" + plain);
  expect_error(replace(s, "name = \"tet\"", "name = \"..\""), "\"..\"",
               "[output] name: '.." + plain);
  expect_error(s + "csv = \"../scene.toml\"\n", "\"../scene.toml\"",
               "[output] csv: '../scene.toml" + plain);
  expect_error(s + "csv = \"/tmp/stats.csv\"\n", "\"/tmp/stats.csv\"",
               "[output] csv: '/tmp/stats.csv" + plain);
  expect_error(s + "csv = \"missing/stats.csv\"\n", "\"missing/stats.csv\"",
               "[output] csv: 'missing/stats.csv" + plain);
  expect_error(s + "csv = \"tet.pvd\"\n", "\"tet.pvd\"",
               "[output] csv: '" + path("out/tet.pvd") + "' is also the file of [output] name");
  expect_error(s + "csv = \"tet_000001.vtu\"\n", "\"tet_000001.vtu\"",
               "[output] csv: '" + path("out/tet_000001.vtu") +
                   "' is also the name of a frame of the series 'tet' (tet_NNNNNN.vtu)");
  expect_error(s + "png = \"a.png\"\ncsv = \"a.png\"\n", "\"a.png\"",
               "[output] png: '" + path("out/a.png") + "' is also the file of [output] csv");
  expect_error(s, "",
               "--final-csv: '" + path("out/tet.pvd") + "' is also the file of [output] name",
               {"--final-csv", path("out/tet.pvd")});
  // The output folder is the scene's own: an output named like an input is refused there.
  std::string here =
      replace(s, "folder = \"" + path("out") + "\"", "folder = \"" + path("") + "\"");
  Result r = run(here + "csv = \"scene.toml\"\n");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err, location(here + "csv = \"scene.toml\"\n", "\"scene.toml\"") + "[output] csv: '" +
                       path("scene.toml") +
                       "' is the scene file: an output must not overwrite an input of the run\n");
  r = run(here + "csv = \"tet.ele\"\n");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("[output] csv: '" + path("tet.ele") +
                       "' is a mesh file of the run: an output must not overwrite an input of "
                       "the run\n"),
            std::string::npos)
      << r.err;
  r = run(here, {"--final-csv", path("tet.node")});
  EXPECT_EQ(r.err, path("scene.toml") + ": error: --final-csv: '" + path("tet.node") +
                       "' is a mesh file of the run: an output must not overwrite an input of "
                       "the run\n");
  // The inputs are intact and no frame was written.
  std::ifstream node(path("tet.node"));
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(node), {}), kNode);
  EXPECT_FALSE(fs::exists(path("tet.pvd")));
}

// --final-csv in a folder that does not exist, or without positions to write, fails before the
// output folder is created; one that fits is written whole (no temporary beside it).
TEST_F(SceneErrors, FinalCsvIsCheckedBeforeTheFirstFrame) {
  const std::string s = fem_scene();
  expect_error(s, "", "--final-csv: the folder '" + path("nowhere") + "' does not exist",
               {"--final-csv", path("nowhere/final.csv")});
  expect_error(replace(s, "position = \"x\"\n", ""), "",
               "--final-csv needs [output] points and position", {"--final-csv", path("f.csv")});
  // /proc takes no new files, not even from root.
  Result r = run(s, {"--final-csv", "/proc/final.csv"});
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err.rfind(path("scene.toml") +
                            ": error: --final-csv: cannot write: /proc/final.csv: cannot create a "
                            "temporary file beside it: ",
                        0),
            0u)
      << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
  r = run(s, {"--final-csv", path("out/final.csv")});  // into the output folder itself
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
  std::ifstream csv(path("out/final.csv"));
  std::string first;
  std::getline(csv, first);
  EXPECT_EQ(first, "x,y,z");
  for (const auto& entry : fs::directory_iterator(path("out")))
    EXPECT_EQ(entry.path().filename().string().find(".csv."), std::string::npos) << entry.path();
}

// Temporaries a killed run could not remove (NAME.pvd.XXXXXX, NAME_NNNNNN.vtu.XXXXXX) go with
// the next run into the folder; other files stay.
TEST_F(SceneErrors, TheNextRunRemovesStaleTemporaries) {
  fs::create_directory(path("out"));
  write("out/tet_000007.vtu.Ab12cD", "half a frame");
  write("out/tet.pvd.x1Y2z3", "half a series");
  write("out/other_000001.vtu.Ab12cD", "not ours");
  write("out/tet_000007.vtu.notes", "not a temporary");
  Result r = run(fem_scene());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(fs::exists(path("out/tet_000007.vtu.Ab12cD")));
  EXPECT_FALSE(fs::exists(path("out/tet.pvd.x1Y2z3")));
  EXPECT_TRUE(fs::exists(path("out/other_000001.vtu.Ab12cD")));
  EXPECT_TRUE(fs::exists(path("out/tet_000007.vtu.notes")));
  EXPECT_TRUE(fs::exists(path("out/tet_000001.vtu")));
}

// A NaN or an infinity stops the run at the frame boundary where it first appears, naming the
// frame, the field, the element and the set; the frames written before it stay, listed in the
// .pvd. --no-finite-check and `finite_check = false` let it through.
TEST_F(SceneErrors, NonFiniteValuesStopTheRunAtTheirFrame) {
  // The fem example with E = 1e300, one vertex pinned and an initial velocity: the first step
  // overflows.
  std::ifstream fem(std::string(SIMIT_SOURCE_DIR) + "/examples/fem/fem.sim");
  std::string program((std::istreambuf_iterator<char>(fem)), {});
  write("fem.sim", replace(program, "const E         = 5e3;", "const E         = 1e300;"));
  std::string s =
      replace(fem_scene(), std::string(SIMIT_SOURCE_DIR) + "/examples/fem/fem.sim", "fem.sim");
  s = replace(s, "frames = 1", "frames = 3");
  s = replace(s, "x = \"position\"\n",
              "x = \"position\"\npinned = \"x + y + z < 0.5\"\nv = [0.1, 0.0, 0.1]\n");
  s += "csv = \"stats.csv\"\n";
  const std::string hint =
      " (--check-finite stops at the statement that makes it; --no-finite-check lets it "
      "through)\n";
  Result r = run(s);
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err, path("scene.toml") +
                       ": error: after frame 1: field 'x' of element 0 of set 'verts' is nan "
                       "(component 0)" +
                       hint);
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(path("out")))
    files.push_back(entry.path().filename().string());
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files, (std::vector<std::string>{"stats.csv", "tet.pvd", "tet_000000.vtu"}));
  std::ifstream pvd(path("out/tet.pvd"));
  std::string series((std::istreambuf_iterator<char>(pvd)), {});
  EXPECT_NE(series.find("file=\"tet_000000.vtu\""), std::string::npos) << series;
  EXPECT_EQ(series.find("tet_000001"), std::string::npos) << series;
  EXPECT_NE(series.find("</VTKFile>"), std::string::npos) << series;
  // Turned off, the run goes on (and writes the NaN frames).
  fs::remove_all(path("out"));
  r = run(s, {"--no-finite-check"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(path("out/tet_000003.vtu")));
  fs::remove_all(path("out"));
  r = run(replace(s, "frames = 3", "frames = 3\nfinite_check = false"));
  EXPECT_EQ(r.status, 0) << r.err;
  fs::remove_all(path("out"));
  expect_error(replace(s, "frames = 3", "frames = 3\nfinite_check = 0"), "0\n[",
               "finite_check: expected true or false");
  // A field expression that divides by zero: stopped before frame 0 is written. (Element 0 is
  // pinned: init zeroes its velocity.)
  r = run(replace(s, "v = [0.1, 0.0, 0.1]", "v = \"1/0\""));
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err, path("scene.toml") +
                       ": error: after init (frame 0): field 'v' of element 1 of set 'verts' is "
                       "inf (component 0)" +
                       hint);
  EXPECT_FALSE(fs::exists(path("out/tet.pvd")));
  EXPECT_FALSE(fs::exists(path("out/tet_000000.vtu")));
  // The same in binary32 fields (--float32), whose check reads their bits as binary32.
  r = run(replace(s, "v = [0.1, 0.0, 0.1]", "v = \"1/0\""), {"--float32"});
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err, path("scene.toml") +
                       ": error: after init (frame 0): field 'v' of element 1 of set 'verts' is "
                       "inf (component 0)" +
                       hint);
  // Finite binary32 values at the top of the range are not taken for infinities: the check
  // after init passes, and the run stops after frame 1 (on this scene's E).
  r = run(replace(s, "v = [0.1, 0.0, 0.1]", "v = [3.4e38, -3.4e38, 0.0]"), {"--float32"});
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err.find("after init (frame 0)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": error: after frame 1: "), std::string::npos) << r.err;
}

// A trivial step on a large generated cloth, so that a run spends its time writing frames.
const char* kWriterProgram = R"(element Point
  x : vector[3](float);
end
element Face
end
extern points : set{Point};
extern faces : set{Face}(points, points, points);
func nudge(inout p : Point)
  p.x(1) = p.x(1) + 0.001;
end
export func step()
  apply nudge to points;
end
)";

// `simit run` killed by SIGTERM while it writes frames: it dies of the signal, removes the
// temporary it was writing, and the .pvd lists exactly the complete frames on disk.
TEST_F(SceneErrors, AKilledRunLeavesNoTemporaries) {
  write("writer.sim", kWriterProgram);
  std::string scene = "program = \"writer.sim\"\nstep = \"step\"\nframes = 1000\n";
  for (const char* set : {"points", "faces"})
    scene += std::string("[sets.") + set +
             "]\ngenerate = \"square_cloth\"\nn = 400\nelements = \"" +
             (std::string(set) == "points" ? "vertices" : "triangles") + "\"\n";
  scene += "[sets.points.fields]\nx = \"position\"\n[output]\nfolder = \"" + path("out") +
           "\"\nname = \"c\"\npoints = \"points\"\nposition = \"x\"\ncells = \"faces\"\n";
  write("scene.toml", scene);
  const std::string scene_path = path("scene.toml");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    freopen("/dev/null", "w", stdout);
    execl(SIMIT_EXE, SIMIT_EXE, "run", scene_path.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Once the .pvd lists frame 0, wait until a later frame's temporary is seen, then kill.
  auto writing = [&] {
    std::error_code ec;
    if (!fs::exists(path("out/c.pvd"), ec)) return false;
    for (const auto& entry : fs::directory_iterator(path("out"), ec))
      if (entry.path().filename().string().find(".vtu.") != std::string::npos) return true;
    return false;
  };
  for (int waited = 0; !writing() && waited < 600000; ++waited) usleep(100);
  ASSERT_TRUE(writing());
  kill(child, SIGTERM);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  std::set<std::string> frames;
  for (const auto& entry : fs::directory_iterator(path("out"))) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "c.pvd" || name.ends_with(".vtu")) << "left behind: " << name;
    if (name.ends_with(".vtu")) frames.insert(name);
  }
  std::ifstream pvd(path("out/c.pvd"));
  std::set<std::string> listed;
  for (std::string line; std::getline(pvd, line);) {
    const size_t at = line.find("file=\"");
    if (at != std::string::npos)
      listed.insert(line.substr(at + 6, line.find('"', at + 6) - at - 6));
  }
  EXPECT_FALSE(listed.empty());
  // The .pvd is rewritten after each frame: a frame renamed into place just before the signal
  // may not be listed yet, but every listed frame is on disk.
  for (const std::string& f : listed) EXPECT_TRUE(frames.count(f)) << f;
  EXPECT_LE(frames.size(), listed.size() + 1);
}

}  // namespace
}  // namespace simit::tools
