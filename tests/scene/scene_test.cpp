// The scene library (simit/scene.h): a scene on a hand-written one-tet mesh (set sizes,
// field values from expressions, the frames run with an extern tensor bound once, the files
// of the series), the fem example's scene on tests/data/bar2k, and located errors.
#include "simit/scene.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "frontend/ast.h"
#include "scene/scene_expr.h"
#include "scene/scene_sets.h"

namespace simit::scene {
namespace {

namespace fs = std::filesystem;

// One tet on (0,0,0), (1,0,0), (0,1,0), (0,0,1) in TetGen's format.
const char* kNode = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
const char* kEle = "1 4 0\n0 0 1 2 3\n";

// init doubles h; step lifts the unpinned vertices by dt and counts its calls in an extern.
const char* kProgram = R"(element Vertex
  x : vector[3](float);
  h : float;
  pinned : bool;
end
element Tet
  w : float;
end
extern verts : set{Vertex};
extern tets : set{Tet}(verts, verts, verts, verts);
extern dt : float;
extern count : int;

func double_h(inout v : Vertex)
  v.h = 2.0 * v.h;
end

func lift(inout v : Vertex)
  if not v.pinned
    v.x(1) = v.x(1) + dt;
  end
end

export func init()
  apply double_h to verts;
end

export func step() -> (n : int, squares : float)
  apply lift to verts;
  count = count + 1;
  n = count;
  squares = verts.h' * verts.h;
end
)";

const char* kScene = R"(program = "tet.sim"
init = "init"
step = "step"
frames = 3
[tensors]
dt = 0.5
count = 10
[sets.verts]
mesh = "tet.node"
elements = "vertices"
[sets.verts.fields]
x = "position"
h = "x + 2 * y + 3 * z"
pinned = "y < 0.5"
[sets.tets]
mesh = "tet.node"
elements = "tets"
[sets.tets.fields]
w = "x + y + z"
[output]
folder = "out"
name = "tet"
points = "verts"
position = "x"
cells = "tets"
point_fields = ["h", "pinned"]
cell_fields = ["w"]
every = 2
csv = "stats.csv"
)";

class SceneTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "simit-scene-test-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    write("tet.node", kNode);
    write("tet.ele", kEle);
    write("tet.sim", kProgram);
    write("tet.toml", kScene);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
  }
  SceneOptions options(const std::string& scene = "tet.toml") const {
    SceneOptions o;
    o.file = path(scene);
    o.output_dir = path("out");
    return o;
  }
  static std::vector<std::string> lines(const std::string& file) {
    std::ifstream in(file);
    std::vector<std::string> out;
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
  }

  fs::path dir_;
};

TEST_F(SceneTest, BuildsTheSetsWithTheirFieldValues) {
  std::ostringstream err;
  std::optional<SceneSets> s = load_scene_sets(path("tet.toml"), false, err);
  ASSERT_TRUE(s) << err.str();
  EXPECT_EQ(s->init, "init");
  EXPECT_EQ(s->step, "step");
  ASSERT_EQ(s->sets.size(), 2u);  // in the order of the TOML tables' names
  EXPECT_EQ(s->sets[0].first, "tets");
  EXPECT_EQ(s->sets[1].first, "verts");
  const runtime::Set& tets = *s->sets[0].second;
  const runtime::Set& verts = *s->sets[1].second;
  EXPECT_EQ(verts.size(), 4);
  EXPECT_EQ(tets.size(), 1);
  EXPECT_EQ(tets.arity(), 4);
  // h = x + 2y + 3z at the vertices; pinned where y < 0.5; w at the centroid (1/4 each).
  const double h[] = {0.0, 1.0, 2.0, 3.0};
  for (int i = 0; i < 4; ++i) {
    EXPECT_DOUBLE_EQ(verts.field("h").at<double>(i)[0], h[i]) << i;
    EXPECT_EQ(verts.field("pinned").at<bool>(i)[0], i != 2) << i;
  }
  EXPECT_DOUBLE_EQ(verts.field("x").at<double>(3)[2], 1.0);
  EXPECT_DOUBLE_EQ(tets.field("w").at<double>(0)[0], 0.75);
  ASSERT_EQ(s->tensors.size(), 2u);
  EXPECT_EQ(s->tensors[0].first, "dt");
  EXPECT_DOUBLE_EQ(s->tensors[0].second.floats()[0], 0.5);
  EXPECT_EQ(s->tensors[1].second.ints()[0], 10);
}

// A tet listed in the other orientation (det[x0-x3 | x1-x3 | x2-x3] > 0) is oriented as the
// scene reads the mesh: its first two vertices swap, so every tet has TetGen's orientation and
// a positive rest volume -det/6. The tets in TetGen's orientation keep their order.
TEST_F(SceneTest, InvertedTetsAreOrientedOnReading) {
  write("tet.ele", "2 4 0\n0 0 1 2 3\n1 1 0 2 3\n");
  std::ostringstream err;
  std::optional<SceneSets> s = load_scene_sets(path("tet.toml"), false, err);
  ASSERT_TRUE(s) << err.str();
  const runtime::Set& tets = *s->sets[0].second;
  ASSERT_EQ(tets.size(), 2);
  for (int e = 0; e < 2; ++e)
    for (int k = 0; k < 4; ++k) EXPECT_EQ(tets.endpoint(e, k), k) << e;
}

TEST_F(SceneTest, Float32FieldsAreSingle) {
  std::ostringstream err;
  std::optional<SceneSets> s = load_scene_sets(path("tet.toml"), true, err);
  ASSERT_TRUE(s) << err.str();
  const runtime::Field& x = s->sets[1].second->field("x");
  EXPECT_TRUE(x.type().single);
  EXPECT_EQ(x.at<float>(2)[1], 1.0f);
}

TEST_F(SceneTest, RunsTheFramesAndWritesTheSeries) {
  SceneOptions o = options();
  o.final_csv = path("final.csv");
  std::ostringstream out, err;
  ASSERT_EQ(run_scene(o, out, err), 0) << err.str();
  EXPECT_NE(out.str().find("tet.toml: tets 1, verts 4; 3 frames"), std::string::npos) << out.str();
  // The extern tensor is bound once: step's increments of `count` carry over between frames.
  EXPECT_NE(out.str().find("n = 11, squares = 56"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("n = 13, squares = 56"), std::string::npos) << out.str();
  // every = 2: frames 0 and 2, and the last one (3), at their times in the .pvd.
  const std::vector<std::string> pvd = lines(path("out/tet.pvd"));
  std::string series;
  for (const std::string& line : pvd) series += line + "\n";
  EXPECT_NE(series.find("timestep=\"0\" group=\"\" part=\"0\" file=\"tet_000000.vtu\""),
            std::string::npos)
      << series;
  EXPECT_NE(series.find("timestep=\"2\" group=\"\" part=\"0\" file=\"tet_000001.vtu\""),
            std::string::npos)
      << series;
  EXPECT_NE(series.find("timestep=\"3\" group=\"\" part=\"0\" file=\"tet_000002.vtu\""),
            std::string::npos)
      << series;
  EXPECT_TRUE(fs::exists(path("out/tet_000002.vtu")));
  EXPECT_FALSE(fs::exists(path("out/tet_000003.vtu")));
  const std::vector<std::string> stats = lines(path("out/stats.csv"));
  ASSERT_EQ(stats.size(), 4u);
  EXPECT_EQ(stats[0], "frame,time,ms,n,squares,assembly_ms,solve_ms");
  EXPECT_EQ(stats[3].substr(0, 4), "3,3,");
  // Only vertex 2 is free: lifted by dt = 0.5 in each of the 3 frames.
  const std::vector<std::string> final_positions = lines(path("final.csv"));
  ASSERT_EQ(final_positions.size(), 5u);
  EXPECT_EQ(final_positions[0], "x,y,z");
  EXPECT_EQ(final_positions[2], "1,0,0");
  EXPECT_EQ(final_positions[3], "0,2.5,0");
}

TEST_F(SceneTest, OpenedOnceRunsAgainFromTheMeshes) {
  SceneOptions o = options();
  o.quiet = true;
  std::ostringstream err;
  std::unique_ptr<Scene> scene = Scene::open(o, err);
  ASSERT_TRUE(scene) << err.str();
  EXPECT_NE(SceneAccess::program(*scene).find_func("step"), nullptr);
  EXPECT_EQ(fs::path(scene->program_path()).filename(), "tet.sim");
  std::ostringstream first, second;
  ASSERT_EQ(scene->run(first, err, 2), 0) << err.str();
  ASSERT_EQ(scene->run(second, err, 2), 0) << err.str();
  EXPECT_EQ(first.str(), second.str());  // fresh sets and tensors each run
  EXPECT_NE(first.str().find("; 2 frames\n2 frames\n"), std::string::npos) << first.str();
  EXPECT_FALSE(fs::exists(path("out")));  // quiet: no output files
}

TEST_F(SceneTest, TheFemExampleOnTheBar) {
  const std::string src = SIMIT_SOURCE_DIR;
  std::ostringstream err;
  std::optional<SceneSets> s = load_scene_sets(src + "/tests/scene/fem_bar2k.toml", false, err);
  ASSERT_TRUE(s) << err.str();
  ASSERT_EQ(s->sets.size(), 2u);
  EXPECT_EQ(s->sets[0].first, "tets");
  EXPECT_EQ(s->sets[0].second->size(), 1151);  // tests/data/bar2k.ele
  EXPECT_EQ(s->sets[1].first, "verts");
  EXPECT_EQ(s->sets[1].second->size(), 439);  // tests/data/bar2k.node
  const runtime::Field& v = s->sets[1].second->field("v");
  EXPECT_DOUBLE_EQ(v.at<double>(17)[0], 0.1);
  EXPECT_DOUBLE_EQ(v.at<double>(17)[1], 0.0);
  ASSERT_EQ(s->tensors.size(), 2u);
  EXPECT_EQ(s->tensors[0].first, "cg_tol");
  EXPECT_DOUBLE_EQ(s->tensors[0].second.floats()[0], 1e-24);
  EXPECT_EQ(s->tensors[1].second.ints()[0], 10000);
}

TEST_F(SceneTest, ErrorsNameTheSceneLineAndColumn) {
  std::string text = kScene;
  text.replace(text.find("elements = \"vertices\""), 21, "elements = \"vertexes\"");
  write("bad.toml", text);
  std::ostringstream out, err;
  EXPECT_EQ(run_scene(options("bad.toml"), out, err), 1);
  EXPECT_EQ(err.str(), path("bad.toml") +
                           ":10:12: error: [sets.verts] elements: 'vertexes' is not one of "
                           "vertices, tets, triangles, edges, tet_edges, boundary_triangles, "
                           "hinges\n");
  EXPECT_FALSE(fs::exists(path("out")));  // nothing written before every check passed
}

TEST_F(SceneTest, AMissingTensorIsNamedWithTheProcedure) {
  std::string text = kScene;
  text.replace(text.find("count = 10\n"), 11, "");
  write("bad.toml", text);
  std::ostringstream out, err;
  EXPECT_EQ(run_scene(options("bad.toml"), out, err), 1);
  EXPECT_EQ(err.str(), path("bad.toml") +
                           ":3:8: error: step: 'step' uses the extern tensor 'count' (int), "
                           "which is not set: add it to [tensors]\n");
}

TEST_F(SceneTest, OpenReportsTheProgramsDiagnostics) {
  write("tet.sim", "export func step()\n  x = ;\nend\n");
  std::ostringstream err;
  EXPECT_EQ(Scene::open(options(), err), nullptr);
  EXPECT_NE(err.str().find("tet.sim:2:"), std::string::npos) << err.str();
  EXPECT_NE(err.str().find("tet.toml: error: the program '"), std::string::npos) << err.str();
}

// The scene file's `executor` key reaches the engine with the options' threshold and check:
// step's apply runs compiled (and checked) in every frame, with the interpreter's values.
TEST_F(SceneTest, TheSceneFileChoosesTheExecutor) {
  write("jit.toml", std::string("executor = \"jit\"\njit_cache = \"off\"\n") + kScene);
  SceneOptions o = options("jit.toml");
  o.executor.threshold = 0;
  o.executor.check = true;
  o.jit_stats = true;
  std::ostringstream out, err;
  std::unique_ptr<Scene> scene = Scene::open(o, err);
  if (!jit_available()) {
    EXPECT_EQ(scene, nullptr);
    EXPECT_EQ(err.str().rfind(path("jit.toml") +
                                  ":1:12: error: executor: this build has no JIT: configure with "
                                  "-DSIMIT_WITH_LLVM=ON",
                              0),
              0u)
        << err.str();
    GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  }
  ASSERT_TRUE(scene) << err.str();
  const ExecutorChoice& x = SceneAccess::executor(*scene);
  EXPECT_EQ(x.kind, ExecutorKind::Jit);
  EXPECT_EQ(x.threshold, 0);
  EXPECT_TRUE(x.check);
  EXPECT_EQ(x.jit_cache, "off");
  ASSERT_EQ(scene->run(out, err, 3), 0) << err.str();
  EXPECT_NE(out.str().find("n = 11, squares = 56"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("n = 13, squares = 56"), std::string::npos) << out.str();
  // Both applies compiled at their first execution (threshold 0): lift ran in 3 frames.
  const size_t table = out.str().find("jit traces:\n");
  ASSERT_NE(table, std::string::npos) << out.str();
  const size_t lift = out.str().find("\n  lift (line ", table);
  ASSERT_NE(lift, std::string::npos) << out.str();
  const std::string row = out.str().substr(lift + 1, out.str().find('\n', lift + 1) - lift - 1);
  EXPECT_TRUE(row.ends_with("  compiled")) << row;
  std::istringstream fields(row.substr(row.find(')') + 1));
  double compile_ms = 0;
  long calls = 0;
  fields >> compile_ms >> calls;
  EXPECT_EQ(calls, 3) << row;
}

// The command line's choice wins over the file's; either's unknown value is an error naming
// the file, the line and the key.
TEST_F(SceneTest, TheCommandLineOverridesTheFileAndBadValuesAreLocated) {
  write("jit.toml", std::string("executor = \"jit\"\n") + kScene);
  SceneOptions o = options("jit.toml");
  o.quiet = true;
  o.executor_given = true;  // --executor interpreter
  std::ostringstream out, err;
  std::unique_ptr<Scene> scene = Scene::open(o, err);
  ASSERT_TRUE(scene) << err.str();
  EXPECT_EQ(SceneAccess::executor(*scene).kind, ExecutorKind::Interpreter);
  EXPECT_EQ(SceneAccess::executor(*scene).jit_cache, "");  // the user's cache: not given

  write("bad.toml",
        std::string("frames = 3\nexecutor = \"jti\"\n") +
            std::string(kScene).replace(std::string(kScene).find("frames = 3\n"), 11, ""));
  EXPECT_EQ(run_scene(options("bad.toml"), out, err), 1);
  EXPECT_EQ(err.str(), path("bad.toml") +
                           ":2:12: error: executor: unknown executor 'jti': valid executors are "
                           "interpreter, jit, gpu\n");
  err.str("");
  write("bad.toml", std::string("jit_cache = 3\n") + kScene);
  EXPECT_EQ(run_scene(options("bad.toml"), out, err), 1);
  EXPECT_EQ(err.str(),
            path("bad.toml") + ":1:13: error: jit_cache: expected a string: \"off\" or a folder\n");
  // --jit-stats with the interpreter would print nothing: refused, naming both ways to the JIT.
  err.str("");
  SceneOptions stats = options();
  stats.jit_stats = true;
  EXPECT_EQ(run_scene(stats, out, err), 1);
  EXPECT_EQ(err.str(), path("tet.toml") +
                           ": error: --jit-stats needs the JIT: --executor jit, or executor = "
                           "\"jit\" in the scene\n");
}

TEST(PositionExpr, EvaluatesOverThePositionAndTheBox) {
  const double p[3] = {1.0, 2.0, 3.0}, lo[3] = {0, 0, 0}, hi[3] = {4, 4, 4};
  EXPECT_DOUBLE_EQ(PositionExpr("x + 2 * y ^ 2 - z").eval(p, lo, hi), 6.0);
  EXPECT_DOUBLE_EQ(PositionExpr("y < 1e-4 or z >= zmax - 1").eval(p, lo, hi), 1.0);
  EXPECT_DOUBLE_EQ(PositionExpr("max(x, sqrt(16))").eval(p, lo, hi), 4.0);
  EXPECT_THROW(PositionExpr("x +"), std::invalid_argument);
}

// The message of the std::invalid_argument that parsing `text` throws, or "no error".
std::string expr_error(const std::string& text) {
  try {
    PositionExpr e(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

std::string repeated(const std::string& s, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) out += s;
  return out;
}

TEST(PositionExpr, NestingIsLimitedAndNamesTheColumn) {
  const double p[3] = {2.0, 0, 0}, lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  // 256 levels are allowed; the 257th '(' (column 257) is one too many.
  EXPECT_DOUBLE_EQ(PositionExpr(repeated("(", 256) + "x" + repeated(")", 256)).eval(p, lo, hi),
                   2.0);
  EXPECT_EQ(expr_error(repeated("(", 10000) + "x" + repeated(")", 10000)),
            "column 257: the expression is nested more than 256 levels deep");
  EXPECT_EQ(expr_error(repeated("-", 10000) + "x"),
            "column 257: the expression is nested more than 256 levels deep");
  EXPECT_EQ(expr_error(repeated("not ", 300) + "x"),
            "column 1025: the expression is nested more than 256 levels deep");
  EXPECT_EQ(expr_error(repeated("sqrt(", 300) + "x" + repeated(")", 300)),
            "column 1285: the expression is nested more than 256 levels deep");
  EXPECT_EQ(expr_error("x" + repeated("^x", 300)),
            "column 514: the expression is nested more than 256 levels deep");
}

TEST(PositionExpr, LengthIsLimited) {
  std::string sum = "x" + repeated("+x", 1000000);
  EXPECT_EQ(expr_error(sum),
            "the expression is 2000001 characters long; at most 65536 are allowed");
}

TEST(PositionExpr, FlatChainsAreNotNesting) {
  const double p[3] = {0.5, 3.0, 0}, lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  // 30,000 terms: far beyond the nesting limit, within the length limit.
  EXPECT_DOUBLE_EQ(PositionExpr("x" + repeated("+x", 29999)).eval(p, lo, hi), 15000.0);
  // Left to right: 1 - 1 - 1 - 1 is -2, and 64 / 2 / 2 * 4 is 64.
  EXPECT_DOUBLE_EQ(PositionExpr("1 - 1 - 1 - 1").eval(p, lo, hi), -2.0);
  EXPECT_DOUBLE_EQ(PositionExpr("64 / 2 / 2 * 4").eval(p, lo, hi), 64.0);
  EXPECT_DOUBLE_EQ(PositionExpr("y - (x + x) - x").eval(p, lo, hi), 1.5);
  EXPECT_DOUBLE_EQ(PositionExpr("(y - x) - (x - y)").eval(p, lo, hi), 5.0);
  EXPECT_DOUBLE_EQ(PositionExpr("x > 0 and y > 2 and x < 0").eval(p, lo, hi), 0.0);
  EXPECT_DOUBLE_EQ(PositionExpr("x < 0 or y < 2 or x > 0").eval(p, lo, hi), 1.0);
  EXPECT_DOUBLE_EQ(PositionExpr(repeated("x < 0 or ", 5000) + "y > 2").eval(p, lo, hi), 1.0);
}

}  // namespace
}  // namespace simit::scene
