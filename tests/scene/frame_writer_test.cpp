// A scene's frames written on a thread of their own (scene/frame_writer.h): the writer runs
// its jobs one at a time in order while the poster goes on, reports a job's failure at the
// next post or wait, and finishes its job before it goes; `simit run`'s frames, written so
// (each after the next frame's step, in the test), are byte for byte those of a host that
// steps the scene (written before step() returns), each with its own frame's field values;
// a frame that cannot be written stops the run, one frame later in the background, and the
// series lists the frames before it; [output] background decides where frames are written,
// also for a host that steps the scene, which then learns of a failed frame a step later.
#include "scene/frame_writer.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "simit/scene.h"

namespace simit::scene {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

TEST(FrameWriter, RunsItsJobsOneAtATimeInOrderWhileThePosterGoesOn) {
  FrameWriter writer;
  writer.wait();  // nothing posted: returns at once
  EXPECT_FALSE(writer.busy());
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::vector<int> done;
  std::atomic<int> running{0}, most{0};
  auto job = [&](int k, bool hold) {
    return [&, k, hold] {
      most = std::max(most.load(), ++running);
      if (hold) released.wait();
      std::this_thread::sleep_for(1ms);
      done.push_back(k);  // only the writer thread touches it until wait()
      --running;
    };
  };
  writer.post(job(0, true));
  // The first job waits for the poster, so post returned before it finished.
  EXPECT_TRUE(writer.busy());
  release.set_value();
  for (int k = 1; k < 6; ++k) writer.post(job(k, false));
  writer.wait();
  EXPECT_FALSE(writer.busy());
  EXPECT_EQ(done, (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(most.load(), 1);
}

TEST(FrameWriter, AJobsFailureIsThrownByTheNextPostOrWaitOnce) {
  FrameWriter writer;
  bool ran = false;
  writer.post([] { throw std::runtime_error("frame 3: disk full"); });
  try {
    writer.post([&] { ran = true; });
    FAIL() << "the failure of the job before was not reported";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "frame 3: disk full");
  }
  writer.wait();
  EXPECT_FALSE(ran);  // the job posted after a failure is not run
  writer.post([] { throw std::runtime_error("frame 4"); });
  EXPECT_THROW(writer.wait(), std::runtime_error);
  EXPECT_NO_THROW(writer.wait());  // reported once
  writer.post([&] { ran = true; });
  writer.wait();
  EXPECT_TRUE(ran);
}

TEST(FrameWriter, FinishesItsJobBeforeItGoesAndDropsItsFailure) {
  std::atomic<bool> finished{false};
  {
    FrameWriter writer;
    writer.post([&] {
      std::this_thread::sleep_for(20ms);
      finished = true;
    });
  }
  EXPECT_TRUE(finished.load());
  {
    FrameWriter writer;
    writer.post([] { throw std::runtime_error("dropped"); });
  }  // no throw from the destructor
}

// One tet; every frame lifts the free vertex and changes the point field `h` and the cell
// field `w`, so that a frame holds values no other frame has.
const char* kNode = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
const char* kEle = "1 4 0\n0 0 1 2 3\n";
const char* kProgram = R"(element Vertex
  x : vector[3](float);
  h : float;
end
element Tet
  w : float;
end
extern verts : set{Vertex};
extern tets : set{Tet}(verts, verts, verts, verts);

func lift(inout v : Vertex)
  v.x(1) = v.x(1) + 0.25 * v.x(0);
  v.h = 3.0 * v.h + 1.0;
end

func grow(inout t : Tet)
  t.w = t.w * 1.5;
end

export func step()
  apply lift to verts;
  apply grow to tets;
end
)";
const char* kScene = R"(program = "tet.sim"
step = "step"
frames = 6
[sets.verts]
mesh = "tet.node"
elements = "vertices"
[sets.verts.fields]
x = "position"
h = "x + 2 * y"
[sets.tets]
mesh = "tet.node"
elements = "tets"
[sets.tets.fields]
w = "1.0"
[output]
folder = "out"
name = "tet"
points = "verts"
position = "x"
cells = "tets"
point_fields = ["h"]
cell_fields = ["w"]
)";

class BackgroundFrames : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "simit-frame-writer-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    std::ofstream(dir_ / "tet.node") << kNode;
    std::ofstream(dir_ / "tet.ele") << kEle;
    std::ofstream(dir_ / "tet.sim") << kProgram;
    std::ofstream(dir_ / "tet.toml") << kScene;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  SceneOptions options(const std::string& out) const {
    SceneOptions o;
    o.file = (dir_ / "tet.toml").string();
    o.output_dir = (dir_ / out).string();
    // In the mesh's order, the arrays of a frame written in its thread are the fields' own.
    o.keep_mesh_order = true;
    return o;
  }
  static std::string bytes(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  // The scene with `output_lines` added to its [output] table, and a fresh output folder
  // "run" holding a folder where frame 2's file goes, so that the rename onto it fails.
  void block_frame_2(const std::string& output_lines) const {
    std::ofstream(dir_ / "tet.toml") << std::string(kScene) + output_lines;
    std::error_code ec;
    fs::remove_all(dir_ / "run", ec);
    fs::create_directories(dir_ / "run" / "tet_000002.vtu");
  }
  std::vector<std::string> names(const std::string& out) const {
    std::vector<std::string> v;
    for (const auto& e : fs::directory_iterator(dir_ / out)) v.push_back(e.path().filename());
    std::sort(v.begin(), v.end());
    return v;
  }

  fs::path dir_;
};

// Writers start a job only at the next post or wait while it lives.
struct HeldJobs {
  HeldJobs() { FrameWriter::hold_jobs_for_test(true); }
  ~HeldJobs() { FrameWriter::hold_jobs_for_test(false); }
};

TEST_F(BackgroundFrames, AreTheFramesOfAHostThatStepsTheScene) {
  // Written beside the run whatever the machine's cores (a host's stepping ignores the key).
  std::ofstream(dir_ / "tet.toml") << std::string(kScene) + "background = true\n";
  std::ostringstream out, err;
  {
    // Each frame is written after the next one's step: it holds its own copies.
    HeldJobs held;
    ASSERT_EQ(run_scene(options("run"), out, err), 0) << err.str();
  }
  // The host's frames are written before each step() returns (no background key).
  std::ofstream(dir_ / "in_turn.toml") << kScene;
  SceneOptions o = options("stepped");
  o.file = (dir_ / "in_turn.toml").string();
  std::unique_ptr<Scene> scene = Scene::open(o, err);
  ASSERT_TRUE(scene) << err.str();
  std::ostringstream stepped_out;
  {
    Stepper stepper(*scene, stepped_out);
    stepper.init();
    for (int k = 0; k < 6; ++k) stepper.step();
    stepper.finish();
  }
  const std::vector<std::string> files = names("run");
  EXPECT_EQ(files, names("stepped"));
  ASSERT_EQ(files.size(), 8u);  // tet.pvd and frames 0 to 6
  for (const std::string& f : files)
    EXPECT_TRUE(bytes(dir_ / "run" / f) == bytes(dir_ / "stepped" / f)) << f << " differs";
  // And each frame holds its own values: vertex 2's h is 2, then 3 h + 1 a frame (frame 3:
  // 67, frame 4: 202).
  auto holds = [&](const std::string& file, double v) {
    return bytes(dir_ / "run" / file)
               .find(std::string(reinterpret_cast<const char*>(&v), sizeof v)) != std::string::npos;
  };
  EXPECT_TRUE(holds("tet_000003.vtu", 67.0));
  EXPECT_FALSE(holds("tet_000003.vtu", 202.0));
  EXPECT_TRUE(holds("tet_000004.vtu", 202.0));
}

TEST_F(BackgroundFrames, AFrameThatCannotBeWrittenStopsTheRun) {
  // [output] background decides where the frames are written: beside the run, frame 2's
  // failure stops it once frame 3 is computed (the progress shows frame 2 done); in turn, at
  // frame 2 itself. Either way with the same message, the series listing frames 0 and 1.
  for (const bool background : {true, false}) {
    SCOPED_TRACE(background ? "background = true" : "background = false");
    block_frame_2(background ? "background = true\n" : "background = false\n");
    std::ostringstream out, err;
    EXPECT_EQ(run_scene(options("run"), out, err), 1);
    EXPECT_NE(err.str().find("tet.toml: error: writing output: "), std::string::npos) << err.str();
    EXPECT_NE(err.str().find("tet_000002.vtu"), std::string::npos) << err.str();
    EXPECT_EQ(out.str().find("frame 2/6") != std::string::npos, background) << out.str();
    EXPECT_NE(out.str().find("frame 1/6"), std::string::npos) << out.str();
    EXPECT_EQ(out.str().find("frame 3/6"), std::string::npos) << out.str();
    // The series lists frames 0 and 1, whose files are complete; nothing else was left.
    const std::string pvd = bytes(dir_ / "run" / "tet.pvd");
    EXPECT_NE(pvd.find("file=\"tet_000001.vtu\""), std::string::npos) << pvd;
    EXPECT_EQ(pvd.find("file=\"tet_000002.vtu\""), std::string::npos) << pvd;
    EXPECT_EQ(names("run"), (std::vector<std::string>{"tet.pvd", "tet_000000.vtu", "tet_000001.vtu",
                                                      "tet_000002.vtu"}));
  }
}

TEST_F(BackgroundFrames, AHostThatStepsLearnsOfAFailedFrameAtTheNextStepOrAtFinish) {
  // In turn by default: frame 2's step() throws. With background = true: the next one does,
  // and finish() reports a failed last-but-one frame when no step follows.
  for (const bool background : {false, true}) {
    SCOPED_TRACE(background ? "background = true" : "no background key");
    block_frame_2(background ? "background = true\n" : "");
    std::ostringstream err, out;
    std::unique_ptr<Scene> scene = Scene::open(options("run"), err);
    ASSERT_TRUE(scene) << err.str();
    Stepper stepper(*scene, out);
    stepper.init();
    stepper.step();
    int failed_at = 0;
    for (int k = 2; k <= 4 && failed_at == 0; ++k) {
      try {
        stepper.step();
      } catch (const Error& e) {
        failed_at = k;
        EXPECT_NE(std::string(e.what()).find("writing output: "), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("tet_000002.vtu"), std::string::npos) << e.what();
      }
    }
    EXPECT_EQ(failed_at, background ? 3 : 2);
  }
  // A failed frame with no step after it: finish() throws.
  block_frame_2("background = true\n");
  std::ostringstream err, out;
  std::unique_ptr<Scene> scene = Scene::open(options("run"), err);
  ASSERT_TRUE(scene) << err.str();
  Stepper stepper(*scene, out);
  stepper.step();
  stepper.step();
  EXPECT_THROW(stepper.finish(), Error);
}

TEST_F(BackgroundFrames, TheKeyIsTrueOrFalse) {
  std::ofstream(dir_ / "tet.toml") << std::string(kScene) + "background = 1\n";
  std::ostringstream out, err;
  EXPECT_EQ(run_scene(options("run"), out, err), 1);
  EXPECT_NE(err.str().find("tet.toml:23:14: error: [output] background: expected true or false"),
            std::string::npos)
      << err.str();
}

}  // namespace
}  // namespace simit::scene
