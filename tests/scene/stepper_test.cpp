// scene::Stepper, a scene run a frame at a time by its host: on the springs bunny it reaches
// the same positions, step results and final CSV as Scene::run (interpreted and compiled),
// its set views stay where they are and hold the live values, a renumbered scene's views carry
// mesh numbers; host writes through the views reach the next frame; errors are thrown as the
// API's, and a SIGINT during a step as Interrupted (stop_on_interrupt). Also simit::read_mesh
// on the bunny's TetGen files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "simit/mesh.h"
#include "simit/scene.h"

namespace simit::scene {
namespace {

namespace fs = std::filesystem;
using Vec = std::array<double, 3>;

const std::string kSource = SIMIT_SOURCE_DIR;
const std::string kBunnyScene = kSource + "/examples/springs/bunny.toml";
const std::string kBunnyNode = kSource + "/examples/data/bunny.1.node";
constexpr int kFrames = 3;

// The whole-number fields of a TetGen file's first line (its counts).
std::vector<long> header_of(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::istringstream fields(line);
  std::vector<long> out;
  for (long v; fields >> v;) out.push_back(v);
  return out;
}

// "x,y,z" then one point a line, 17 significant digits: every double read back exactly.
std::vector<Vec> read_xyz(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "x,y,z") << path;
  std::vector<Vec> out;
  while (std::getline(in, line)) {
    Vec p{};
    const char* s = line.c_str();
    for (double& c : p) {
      char* end = nullptr;
      c = std::strtod(s, &end);
      s = *end == ',' ? end + 1 : end;
    }
    out.push_back(p);
  }
  return out;
}

// A CSV with a header line, as columns of numbers by name.
std::map<std::string, std::vector<double>> read_columns(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  std::istringstream header(line);
  for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  std::map<std::string, std::vector<double>> out;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    std::string cell;
    for (size_t k = 0; k < names.size() && std::getline(row, cell, ','); ++k)
      out[names[k]].push_back(std::strtod(cell.c_str(), nullptr));
  }
  return out;
}

const SetView& set_named(const Stepper& s, const std::string& name) {
  for (const SetView& v : s.sets())
    if (v.name == name) return v;
  throw std::runtime_error("no set " + name);
}

const FieldView& field_named(const SetView& set, const std::string& name) {
  for (const FieldView& f : set.fields)
    if (f.name == name) return f;
  throw std::runtime_error("no field " + name + " in " + set.name);
}

class TempFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "simit-stepper-test-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
  }
  static std::unique_ptr<Scene> open(const SceneOptions& o) {
    std::ostringstream err;
    std::unique_ptr<Scene> scene = Scene::open(o, err);
    EXPECT_TRUE(scene) << err.str();
    return scene;
  }

  fs::path dir_;
};

// --- the springs bunny against Scene::run ---------------------------------------------

class StepperBunny : public TempFolder, public ::testing::WithParamInterface<ExecutorKind> {
 protected:
  SceneOptions bunny_options() const {
    SceneOptions o;
    o.file = kBunnyScene;
    o.frames = kFrames;
    o.keep_mesh_order = true;
    o.executor.kind = GetParam();
    o.executor_given = true;
    o.executor.jit_cache = "off";
    o.jit_cache_given = true;
    return o;
  }
};

TEST_P(StepperBunny, FramesEqualSceneRunAndTheViewsStayPut) {
  if (GetParam() == ExecutorKind::Jit && !jit_available()) GTEST_SKIP() << "no JIT in this build";
  // Scene::run: the reference final positions and per-frame statistics.
  SceneOptions ro = bunny_options();
  ro.output_dir = path("run");
  ro.final_csv = path("run_final.csv");
  std::unique_ptr<Scene> reference = open(ro);
  ASSERT_TRUE(reference);
  std::ostringstream run_out, run_err;
  ASSERT_EQ(reference->run(run_out, run_err), 0) << run_err.str();
  const std::vector<Vec> final_x = read_xyz(path("run_final.csv"));
  std::map<std::string, std::vector<double>> stats = read_columns(path("run/bunny_stats.csv"));
  ASSERT_EQ(stats["frame"].size(), size_t{kFrames});

  SceneOptions so = bunny_options();
  so.output_dir = path("step");
  so.final_csv = path("step_final.csv");
  std::unique_ptr<Scene> scene = open(so);
  ASSERT_TRUE(scene);
  EXPECT_EQ(scene->frames(), kFrames);
  std::ostringstream out;
  Stepper stepper(*scene, out);

  // The sets as the mesh files give them, in the files' order.
  const std::vector<long> nodes = header_of(kBunnyNode);
  const std::vector<long> edges = header_of(kSource + "/examples/data/bunny.1.edge");
  const SetView& points = set_named(stepper, "points");
  const SetView& springs = set_named(stepper, "springs");
  ASSERT_EQ(points.size, nodes.at(0));
  EXPECT_EQ(springs.size, edges.at(0));
  EXPECT_EQ(points.arity, 0);
  EXPECT_EQ(springs.arity, 2);
  EXPECT_EQ(springs.endpoint_sets, (std::vector<std::string>{"points", "points"}));
  ASSERT_NE(springs.endpoints, nullptr);
  EXPECT_EQ(points.mesh_numbers, nullptr);
  EXPECT_EQ(springs.mesh_numbers, nullptr);
  const FieldView& x = field_named(points, "x");
  EXPECT_EQ(x.type, (FieldType{ComponentKind::Float, {3}, false}));
  EXPECT_EQ(field_named(points, "pinned").type, (FieldType{ComponentKind::Bool, {}, false}));

  // Before init: x is the node file's points rescaled to [0, 1] on each axis (the scene's
  // expressions), pinned where the rescaled z < 0.1.
  const MeshData mesh = read_mesh(kBunnyNode);
  ASSERT_EQ(mesh.points.size(), size_t(points.size));
  Vec lo = mesh.points[0], hi = mesh.points[0];
  for (const Vec& p : mesh.points)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  const double* xs = static_cast<const double*>(x.data);
  const bool* pinned = static_cast<const bool*>(field_named(points, "pinned").data);
  for (int i = 0; i < points.size; ++i) {
    for (int d = 0; d < 3; ++d)
      ASSERT_DOUBLE_EQ(xs[3 * i + d], (mesh.points[i][d] - lo[d]) / (hi[d] - lo[d])) << i;
    ASSERT_EQ(pinned[i], (mesh.points[i][2] - lo[2]) / (hi[2] - lo[2]) < 0.1) << i;
  }
  std::vector<const void*> data;
  for (const SetView& s : stepper.sets())
    for (const FieldView& f : s.fields) data.push_back(f.data);

  EXPECT_FALSE(stepper.initialised());
  EXPECT_EQ(stepper.frame(), 0);
  stepper.init();
  EXPECT_TRUE(stepper.initialised());
  EXPECT_EQ(stepper.frame(), 0);
  EXPECT_THROW(stepper.init(), Error);  // once

  for (int n = 1; n <= kFrames; ++n) {
    const std::vector<std::pair<std::string, DenseResult>> r = stepper.step();
    EXPECT_EQ(stepper.frame(), n);
    ASSERT_EQ(r.size(), 3u);
    EXPECT_EQ(r[0].first, "cg_iterations");
    EXPECT_EQ(r[1].first, "cg_residual");
    EXPECT_EQ(r[2].first, "energy");
    ASSERT_EQ(r[0].second.kind(), ComponentKind::Int);
    ASSERT_EQ(r[2].second.kind(), ComponentKind::Float);
    const double energy = r[2].second.floats()[0];
    EXPECT_TRUE(std::isfinite(energy));
    // The same frame of Scene::run (its CSV prints 17 significant digits: equal bits).
    EXPECT_EQ(double(r[0].second.ints()[0]), stats["cg_iterations"][n - 1]) << n;
    EXPECT_EQ(r[1].second.floats()[0], stats["cg_residual"][n - 1]) << n;
    EXPECT_EQ(energy, stats["energy"][n - 1]) << n;
  }

  // The views still point at the live fields: after the frames they hold Scene::run's result.
  std::vector<const void*> after;
  for (const SetView& s : stepper.sets())
    for (const FieldView& f : s.fields) after.push_back(f.data);
  EXPECT_EQ(after, data);
  ASSERT_EQ(final_x.size(), size_t(points.size));
  for (int i = 0; i < points.size; ++i)
    for (int d = 0; d < 3; ++d) ASSERT_EQ(xs[3 * i + d], final_x[i][d]) << i << " " << d;

  // finish() writes what a run writes after its last frame.
  EXPECT_FALSE(fs::exists(path("step_final.csv")));
  stepper.finish();
  const std::vector<Vec> stepped_final = read_xyz(path("step_final.csv"));
  EXPECT_EQ(stepped_final, final_x);
  EXPECT_TRUE(fs::exists(path("step/bunny.pvd")));
  EXPECT_TRUE(fs::exists(path("step/bunny_stats.csv")));
}

INSTANTIATE_TEST_SUITE_P(Executors, StepperBunny,
                         ::testing::Values(ExecutorKind::Interpreter, ExecutorKind::Jit),
                         [](const auto& info) { return std::string(executor_name(info.param)); });

// Without keep_mesh_order the scene's default renumbering applies: each view carries its mesh
// numbers, and element i holds what the mesh's element mesh_numbers[i] holds in mesh order.
TEST_F(TempFolder, ARenumberedScenesViewsCarryMeshNumbers) {
  SceneOptions o;
  o.file = kBunnyScene;
  o.quiet = true;
  o.keep_mesh_order = true;
  std::unique_ptr<Scene> kept_scene = open(o);
  o.keep_mesh_order = false;
  std::unique_ptr<Scene> renumbered_scene = open(o);
  ASSERT_TRUE(kept_scene && renumbered_scene);
  std::ostringstream out;
  Stepper kept(*kept_scene, out), renumbered(*renumbered_scene, out);

  for (const std::string name : {"points", "springs"}) {
    const SetView& k = set_named(kept, name);
    const SetView& r = set_named(renumbered, name);
    ASSERT_EQ(r.size, k.size);
    ASSERT_NE(r.mesh_numbers, nullptr) << name;
    std::vector<int32_t> sorted(r.mesh_numbers, r.mesh_numbers + r.size);
    std::sort(sorted.begin(), sorted.end());
    for (int i = 0; i < r.size; ++i) ASSERT_EQ(sorted[i], i) << name << ": not a permutation";
    bool moved = false;
    for (int i = 0; i < r.size && !moved; ++i) moved = r.mesh_numbers[i] != i;
    EXPECT_TRUE(moved) << name << ": the default order is the mesh's";
  }

  const SetView& kp = set_named(kept, "points");
  const SetView& rp = set_named(renumbered, "points");
  for (const FieldView& rf : rp.fields) {
    const FieldView& kf = field_named(kp, rf.name);
    ASSERT_EQ(rf.type, kf.type);
    const ComponentKind kind = rf.type.kind;
    size_t bytes = kind == ComponentKind::Bool      ? 1
                   : kind == ComponentKind::Int     ? 4
                   : kind == ComponentKind::Complex ? 16
                                                    : 8;
    for (int d : rf.type.dims) bytes *= d;
    for (int i = 0; i < rp.size; ++i)
      ASSERT_EQ(std::memcmp(static_cast<const char*>(rf.data) + i * bytes,
                            static_cast<const char*>(kf.data) + rp.mesh_numbers[i] * bytes, bytes),
                0)
          << rf.name << " of element " << i;
  }
  // A spring's endpoints, in mesh numbers, are those of its spring in mesh order.
  const SetView& rs = set_named(renumbered, "springs");
  const SetView& ks = set_named(kept, "springs");
  for (int e = 0; e < rs.size; ++e)
    for (int k = 0; k < 2; ++k)
      ASSERT_EQ(rp.mesh_numbers[rs.endpoints[2 * e + k]], ks.endpoints[2 * rs.mesh_numbers[e] + k])
          << "spring " << e;
}

// --- a one-tet scene: host writes through the views, errors -------------------------------

// One tet on (0,0,0), (1,0,0), (0,1,0), (0,0,1) in TetGen's format.
const char* kNode = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
const char* kEle = "1 4 0\n0 0 1 2 3\n";

// step lifts every vertex by dt, counts its calls, and (when `bad`) reads out of range on
// line 24. `h` sets how long each vertex's loop in `spin` runs.
const char* kProgram = R"(element Vertex
  x : vector[3](float);
  h : float;
end
element Tet
  w : float;
end
extern verts : set{Vertex};
extern tets : set{Tet}(verts, verts, verts, verts);
extern dt : float;
extern count : int;
extern bad : bool;

func lift(inout v : Vertex)
  v.x(1) = v.x(1) + dt;
end

export func step() -> n : int
  apply lift to verts;
  count = count + 1;
  n = count;
  v = [1, 2, 3]';
  if bad
    n = v(count);
  end
end

func spin_one(inout v : Vertex)
  var k = 0.0;
  while k < v.h
    k = k + 1.0;
  end
  v.x(0) = k;
end

export func spin()
  apply spin_one to verts;
end
)";

std::string tet_scene(const std::string& step, bool bad) {
  return "program = \"tet.sim\"\nstep = \"" + step + "\"\nframes = 2\n[tensors]\ndt = 0.5\n" +
         "count = 10\nbad = " + (bad ? "true" : "false") +
         "\n[sets.verts]\nmesh = \"tet.node\"\nelements = \"vertices\"\n"
         "[sets.verts.fields]\nx = \"position\"\nh = \"x + 2 * y + 3 * z\"\n"
         "[sets.tets]\nmesh = \"tet.node\"\nelements = \"tets\"\n";
}

class StepperTet : public TempFolder {
 protected:
  void SetUp() override {
    TempFolder::SetUp();
    write("tet.node", kNode);
    write("tet.ele", kEle);
    write("tet.sim", kProgram);
    write("tet.toml", tet_scene("step", false));
  }
  SceneOptions options(const std::string& scene = "tet.toml") const {
    SceneOptions o;
    o.file = path(scene);
    o.quiet = true;
    o.keep_mesh_order = true;  // vertex i is line i of tet.node
    return o;
  }
};

TEST_F(StepperTet, HostWritesThroughTheViewsReachTheNextFrame) {
  std::unique_ptr<Scene> scene = open(options());
  ASSERT_TRUE(scene);
  EXPECT_EQ(scene->frames(), 2);
  std::ostringstream out;
  Stepper stepper(*scene, out);
  double* x = static_cast<double*>(field_named(set_named(stepper, "verts"), "x").data);
  EXPECT_EQ(x[3 * 2 + 1], 1.0);                                         // vertex 2 is (0, 1, 0)
  std::vector<std::pair<std::string, DenseResult>> r = stepper.step();  // init first
  EXPECT_TRUE(stepper.initialised());
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, "n");
  EXPECT_EQ(r[0].second.ints()[0], 11);
  EXPECT_EQ(x[3 * 2 + 1], 1.5);
  x[3 * 2 + 1] = 10.0;  // the host moves vertex 2 between frames
  x[3 * 3 + 1] = -4.0;
  r = stepper.step();
  EXPECT_EQ(r[0].second.ints()[0], 12);
  EXPECT_EQ(x[3 * 2 + 1], 10.5);
  EXPECT_EQ(x[3 * 3 + 1], -3.5);
  EXPECT_EQ(x[3 * 1 + 1], 1.0);  // vertex 1: 0 + 2 * 0.5
  EXPECT_EQ(stepper.frame(), 2);
  EXPECT_NO_THROW(stepper.finish());  // quiet: nothing to write
}

TEST_F(StepperTet, ARunTimeErrorInStepThrowsRuntimeErrorNamingTheLine) {
  write("bad.toml", tet_scene("step", true));
  std::unique_ptr<Scene> scene = open(options("bad.toml"));
  ASSERT_TRUE(scene);
  std::ostringstream out;
  Stepper stepper(*scene, out);
  stepper.init();
  try {
    stepper.step();
    FAIL() << "no run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.line(), 24) << e.what();
    const std::string text = e.what();
    EXPECT_NE(text.find("tet.sim:24:"), std::string::npos) << text;
    EXPECT_NE(text.find("index 11 is out of range for a dimension of size 3"), std::string::npos)
        << text;
  }
  EXPECT_EQ(stepper.frame(), 0);  // the frame did not happen
}

TEST_F(StepperTet, SceneFileErrorsThrowError) {
  // A tensor the step needs and the scene does not set: found when the Stepper is made.
  std::string text = tet_scene("step", false);
  text.replace(text.find("count = 10\n"), 11, "");
  write("missing.toml", text);
  std::unique_ptr<Scene> scene = open(options("missing.toml"));
  ASSERT_TRUE(scene);
  std::ostringstream out;
  try {
    Stepper stepper(*scene, out);
    FAIL() << "the scene was accepted";
  } catch (const RuntimeError& e) {
    FAIL() << "a scene error thrown as a run-time error: " << e.what();
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path("missing.toml") + ":2:8: error: step: 'step' uses the extern tensor "
                                               "'count' (int), which is not set"),
              std::string::npos)
        << what;
  }
  // A mesh the scene names and that is not there: read when the Stepper builds the sets.
  text = tet_scene("step", false);
  for (size_t at; (at = text.find("tet.node")) != std::string::npos;)
    text.replace(at, 8, "gone.node");
  write("gone.toml", text);
  std::unique_ptr<Scene> gone = open(options("gone.toml"));
  ASSERT_TRUE(gone);
  try {
    Stepper stepper(*gone, out);
    FAIL() << "a missing mesh was accepted";
  } catch (const RuntimeError& e) {
    FAIL() << "a mesh error thrown as a run-time error: " << e.what();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path("gone.toml")), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("gone.node"), std::string::npos) << e.what();
  }
}

// SceneOptions::stop_on_interrupt: a SIGINT during step() throws Interrupted; the stepper goes
// on afterwards (here after the host shortened the loop through the view).
std::atomic<int> g_counted_sigints{0};
extern "C" void count_sigint(int) { g_counted_sigints.fetch_add(1); }

void (*current_sigint_handler())(int) {
  struct sigaction now {};
  sigaction(SIGINT, nullptr, &now);
  return now.sa_handler;
}

TEST_F(StepperTet, ASigintStopsAStepWithInterrupted) {
  write("spin.toml", tet_scene("spin", false));
  SceneOptions o = options("spin.toml");
  o.stop_on_interrupt = true;
  std::unique_ptr<Scene> scene = open(o);
  ASSERT_TRUE(scene);
  std::ostringstream out;
  Stepper stepper(*scene, out);
  double* h = static_cast<double*>(field_named(set_named(stepper, "verts"), "h").data);
  h[3] = 1e8;  // about half a minute interpreted: a failed interrupt ends instead of hanging
  stepper.init();

  // What SIGINT did before: count, so that a signal reaching it is seen and survived.
  struct sigaction counting {
  }, previous{};
  g_counted_sigints = 0;
  counting.sa_handler = count_sigint;
  sigemptyset(&counting.sa_mask);
  sigaction(SIGINT, &counting, &previous);
  std::atomic<bool> over{false}, sent{false};
  std::thread sender([&] {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!over && std::chrono::steady_clock::now() < deadline) {
      if (current_sigint_handler() != count_sigint) {  // the step's handler is in place
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        sent = true;
        kill(getpid(), SIGINT);
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  std::string message;
  try {
    stepper.step();
  } catch (const Interrupted& e) {
    message = e.what();
  } catch (...) {
  }
  over = true;
  sender.join();
  const auto handler_after = current_sigint_handler();
  sigaction(SIGINT, &previous, nullptr);
  ASSERT_TRUE(sent) << "the step never installed its SIGINT handler";
  EXPECT_FALSE(message.empty()) << "the step was not interrupted";
  EXPECT_EQ(g_counted_sigints, 0);
  EXPECT_EQ(handler_after, count_sigint);
  EXPECT_EQ(stepper.frame(), 0);

  h[3] = 5.0;
  stepper.step();
  EXPECT_EQ(stepper.frame(), 1);
  const double* x = static_cast<const double*>(field_named(set_named(stepper, "verts"), "x").data);
  EXPECT_EQ(x[3 * 3], 5.0);  // the loop ran to h
  EXPECT_EQ(x[3 * 2], 2.0);  // vertex 2: h = 2
}

// --- simit::read_mesh -------------------------------------------------------------------

TEST_F(TempFolder, ReadMeshReadsTheTetGenFamily) {
  const MeshData m = read_mesh(kBunnyNode);
  const std::string base = kSource + "/examples/data/bunny.1";
  EXPECT_EQ(long(m.points.size()), header_of(base + ".node").at(0));
  EXPECT_EQ(long(m.tets.size()), header_of(base + ".ele").at(0));
  EXPECT_EQ(long(m.edges.size()), header_of(base + ".edge").at(0));
  EXPECT_TRUE(m.triangles.empty());  // no bunny.1.face
  // The first lines as the files write them (0-based indices).
  std::ifstream node(base + ".node");
  std::string line;
  std::getline(node, line);
  std::getline(node, line);
  std::istringstream first(line);
  int index = -1;
  std::string coords[3];
  first >> index >> coords[0] >> coords[1] >> coords[2];
  EXPECT_EQ(index, 0);
  for (int d = 0; d < 3; ++d) EXPECT_EQ(m.points[0][d], std::strtod(coords[d].c_str(), nullptr));
  EXPECT_EQ(m.edges[0], (std::array<int, 2>{3169, 2323}));
  // Tet 0 is 2342 1528 2323 3169 in the file; it comes back in TetGen's orientation
  // (det[x0-x3 | x1-x3 | x2-x3] < 0), with its first two vertices swapped if it had the other.
  const std::array<int, 4> t = m.tets[0];
  EXPECT_TRUE(t == (std::array<int, 4>{2342, 1528, 2323, 3169}) ||
              t == (std::array<int, 4>{1528, 2342, 2323, 3169}));
  Vec e[3];
  for (int k = 0; k < 3; ++k)
    for (int d = 0; d < 3; ++d) e[k][d] = m.points[t[k]][d] - m.points[t[3]][d];
  const double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                     e[1][0] * (e[0][1] * e[2][2] - e[0][2] * e[2][1]) +
                     e[2][0] * (e[0][1] * e[1][2] - e[0][2] * e[1][1]);
  EXPECT_LT(det, 0.0);
}

TEST_F(TempFolder, ReadMeshErrorsNameTheFile) {
  const std::string missing = path("no_such.node");
  try {
    (void)read_mesh(missing);
    FAIL() << "a missing file was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  write("broken.node", "3 3 0 0\n0 0 0 0\n1 1 0\n");
  try {
    (void)read_mesh(path("broken.node"));
    FAIL() << "a truncated file was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.node"), std::string::npos) << e.what();
  }
  write("points.xyz", "0 0 0\n");
  EXPECT_THROW((void)read_mesh(path("points.xyz")), Error);
}

}  // namespace
}  // namespace simit::scene
