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

#include "simit/executor.h"
#include "simit/program.h"

namespace simit::scene {

class Distributed;  // scene/distributed.h

struct SceneOptions {
  std::string file;        // the .toml scene
  int frames = -1;         // overrides the scene's `frames` when >= 0
  std::string output_dir;  // overrides [output] folder when not empty
  std::string final_csv;   // when set: the last frame's positions as "x,y,z" lines
  std::string png;         // overrides [output] png when not empty (relative to the current folder)
  bool float32 = false;
  bool check_finite = false;  // stop at the statement that produces the first NaN or infinity
  // Check the float fields of the sets and step's float results after init and after every
  // frame, stopping at the first NaN or infinity (the scene's `finite_check = false`, or this
  // option false, turns it off).
  bool finite_check = true;
  // What runs the frames (dumps print to the run's `out`). The scene file's `executor`,
  // `threads` and `jit_cache` keys choose the kind, the thread count and the cache unless these
  // flags say the options did.
  ExecutorChoice executor;
  bool executor_given = false;   // `executor.kind` was given (`--executor`): the file's is ignored
  bool threads_given = false;    // `executor.threads` was given (`--threads`): likewise
  bool jit_cache_given = false;  // `executor.jit_cache` was given (`--jit-cache`): likewise
  bool jit_stats = false;        // jit: print each trace's figures after the run
  bool progress_line = false;    // rewrite one progress line (a terminal) instead of plain lines
  // No output files and no timings (simit debug: its transcript must be reproducible).
  bool quiet = false;
  // Build every set in its mesh's own order, whatever the scene's `reorder` key says (a host
  // that indexes the sets by mesh numbers).
  bool keep_mesh_order = false;
  // While a run or a Stepper call runs, the first SIGINT (Ctrl-C) stops it at its next
  // statement with an error that says so (Stepper: Interrupted) instead of ending the process.
  bool stop_on_interrupt = false;
  // A run on MPI ranks (`simit run --distributed`): each rank runs the program over its part of
  // the sets and rank 0 writes the output (scene/distributed.h); null in one process.
  std::shared_ptr<Distributed> distributed;
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
  // The frames a run makes: the options' when given (>= 0), else the scene file's.
  int frames() const;

  // Builds the sets afresh, checks every binding and the output before the first frame, runs
  // `init` and `frames` frames (the scene's, or the options', when < 0) and writes the output.
  // Prints what the program prints and the progress to `out`. Returns 0, or 1 with the first
  // problem (the scene, a mesh, a run-time error) on `err`.
  int run(std::ostream& out, std::ostream& err, int frames = -1);

 private:
  friend struct SceneAccess;  // the REPL and the debugger reach the program and sets inside
  friend class Stepper;
  struct Impl;
  explicit Scene(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// One field of a set a Stepper built: its storage stays where it is for the Stepper's life.
struct FieldView {
  std::string name;
  FieldType type;
  void* data = nullptr;  // element after element, each type.dims components row-major
};

// One set of a scene as a Stepper built it.
struct SetView {
  std::string name;
  int size = 0;
  // Edge sets: the names of the endpoint sets and `arity` endpoint indices per element.
  std::vector<std::string> endpoint_sets;
  int arity = 0;
  const int32_t* endpoints = nullptr;
  std::vector<FieldView> fields;
  // Element i's number in the mesh, when the scene renumbered the mesh; null: element i is
  // number i.
  const int32_t* mesh_numbers = nullptr;
};

// A scene run a frame at a time by its host (Python's Scene): the same checks, bindings,
// output and errors as Scene::run, with the sets open to the host between frames. Errors throw:
// simit::Error for the scene, its meshes and its output; RuntimeError for a run-time error
// or a non-finite value (with the frame); Interrupted for Ctrl-C (stop_on_interrupt).
class Stepper {
 public:
  // Builds the sets from the meshes (fields as the scene initialises them); runs nothing.
  // Prints and messages go to `out`, which must outlive the Stepper.
  Stepper(Scene& scene, std::ostream& out);
  ~Stepper();
  Stepper(const Stepper&) = delete;
  Stepper& operator=(const Stepper&) = delete;

  const std::vector<SetView>& sets() const;
  // Checks the bindings and the output, runs the scene's `init` and writes frame 0. Once.
  void init();
  bool initialised() const;
  // One frame (init() first when it has not run); the step's dense results by name. Its
  // output files are written when it returns, unless the scene's [output] background = true:
  // then they are written while the next step runs, complete at its return or at finish(),
  // which throw the failure of a frame that could not be written.
  std::vector<std::pair<std::string, DenseResult>> step();
  int frame() const;  // frames run
  // Writes what a run writes after its last frame (the picture, --final-csv). Again only
  // after further frames.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// `simit run SCENE.toml`: open, then run. Returns 0 or 1 as Scene::run.
int run_scene(const SceneOptions& options, std::ostream& out, std::ostream& err);

// Makes SIGINT and SIGTERM remove the output file being written (its temporary) before the
// process dies of the signal, so that a killed run leaves only complete files. Process-wide;
// for command-line programs, once before the first run.
void remove_temporaries_on_signals();

}  // namespace simit::scene
