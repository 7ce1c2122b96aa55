// Scenes: a TOML file that binds a program's extern sets to meshes, says what to run and what
// to write (README.md, "Scenes"). A scene is read and its program compiled once; each run
// builds the sets from the meshes, runs `init` once and `step` per frame through the engine,
// and writes a ParaView series, a per-frame CSV and a quick-look PNG.
#pragma once

#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "runtime/set.h"
#include "runtime/tensor.h"

namespace simit::interp {
class Trap;
}
namespace simit::frontend::ast {
struct Program;
}

namespace simit::scene {

struct SceneOptions {
  std::string file;        // the .toml scene
  int frames = -1;         // overrides the scene's `frames` when >= 0
  std::string output_dir;  // overrides [output] folder when not empty
  std::string final_csv;   // when set: the last frame's positions as "x,y,z" lines
  std::string png;         // overrides [output] png when not empty (relative to the current folder)
  bool float32 = false;
  bool check_finite = false;
  bool progress_line = false;  // rewrite one progress line (a terminal) instead of plain lines
  // simit debug: no output files, no timings (its transcript must be reproducible), and the
  // interpreter's trap point switched through this (interp/hook.h).
  bool quiet = false;
  interp::Trap* trap = nullptr;
};

// A scene's sets built from its meshes with their fields initialised, and its extern tensors,
// before anything runs: what the REPL binds to every statement (`:scene`).
struct SceneSets {
  std::string path;          // the scene file
  std::string program_path;  // the program it names
  std::string init, step;    // its procedures (init may be empty)
  // Extern sets by name, in the scene's order; owned by `owner`.
  std::vector<std::pair<std::string, runtime::Set*>> sets;
  // Extern tensors by name, with the shapes the program declares.
  std::vector<std::pair<std::string, runtime::Tensor>> tensors;
  std::shared_ptr<void> owner;
};

class Scene {
 public:
  // Reads the scene file and compiles its program, once. On a problem reports it on `err`
  // (`SCENE[:line:col]: error: ...`, after the program's diagnostics) and returns null.
  static std::unique_ptr<Scene> open(const SceneOptions& options, std::ostream& err);
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  const std::string& program_path() const;
  // The compiled program the runs execute (the debugger resolves breakpoints against it).
  const frontend::ast::Program& program() const;

  // Builds the sets afresh, checks every binding and the output before the first frame, runs
  // `init` and `frames` frames (the scene's, or the options', when < 0) and writes the output.
  // Prints what the program prints and the progress to `out`. Returns 0, or 1 with the first
  // problem (the scene, a mesh, a run-time error) on `err`.
  int run(std::ostream& out, std::ostream& err, int frames = -1);
  // Builds the sets afresh and reads the tensors, running nothing; nullopt after reporting a
  // problem on `err`.
  std::optional<SceneSets> build(std::ostream& err);

 private:
  struct Impl;
  explicit Scene(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// `simit run SCENE.toml`: open, then run. Returns 0 or 1 as Scene::run.
int run_scene(const SceneOptions& options, std::ostream& out, std::ostream& err);
// The REPL's `:scene`: open, then build (float fields in binary32 when `float32`).
std::optional<SceneSets> load_scene_sets(const std::string& path, bool float32, std::ostream& err);

}  // namespace simit::scene
