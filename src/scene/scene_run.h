// One run of a scene: its sets built afresh from the cached meshes, its tensors read, both
// bound once to an engine over the scene's compiled program, then `init` once and `step` per
// frame, with the output written and the progress printed as it goes.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "api/engine.h"
#include "scene/distributed.h"
#include "scene/mesh_binding.h"
#include "scene/mesh_cache.h"
#include "scene/output_series.h"
#include "scene/scene_file.h"
#include "scene/scene_tensors.h"
#include "simit/scene.h"

namespace simit::scene {

// The program stopped with a run-time error; the message is complete (file:line:col and the
// active calls). `line`: the program's line (0 when none); `interrupted`: Ctrl-C stopped it.
struct RunFailure : std::runtime_error {
  explicit RunFailure(const std::string& message, int line = 0, bool interrupted = false)
      : std::runtime_error(message), line(line), interrupted(interrupted) {}
  int line;
  bool interrupted;
};

// What one frame gave: the step's results, its time and the results the scene's stats name.
struct FrameResult {
  std::vector<interp::Value> results;
  double ms = 0.0, assembly_ms = 0.0;
  std::vector<double> stats;
};

class SceneRun {
 public:
  // `trap`: the interpreter's trap point switch (the step debugger), or null. `reorder`: how
  // the meshes are renumbered (Reorder::Off keeps the sets in each mesh's own order).
  SceneRun(const SceneFile& file, const SceneOptions& options, MeshCache& meshes, Reorder reorder,
           interp::Trap* trap = nullptr)
      : file_(file),
        options_(options),
        meshes_(meshes),
        reorder_(reorder),
        trap_(trap),
        output_(file, options) {}

  // Reads [tensors] and builds [sets]. Throws SceneError.
  void build();
  // Checks the output and what init and step need, opens the output, runs `frames` frames
  // and prints the progress to `out`. Throws SceneError, RunFailure, runtime::MeshError.
  void run(int frames, std::ostream& out);

  // The same run a frame at a time (scene::Stepper), after build(): prepare() checks and
  // binds (print goes to `out`), initialise() runs init and writes frame 0, frame() runs and
  // writes one frame, finish() writes what a run writes after its last frame. Same errors.
  void prepare(std::ostream& out);
  void initialise(bool last);
  FrameResult frame(int frame, bool last);
  void finish(int last_frame);
  const frontend::ast::FuncDecl& step_function() const;
  // --jit-stats: what the JIT made of the run, once; also after run() threw (a run-time
  // error, a NaN stop, Ctrl-C), when it is needed most. Nothing without the option or before
  // the engine exists.
  void print_jit_stats(std::ostream& out);

  const BoundSets& sets() const { return sets_; }
  const std::map<std::string, SceneTensor>& tensors() const { return tensors_; }

 private:
  void check_needs(const std::string& key, const std::string& name) const;
  api::EngineOptions engine_options(std::ostream& out) const;
  double run_frames(int frames, std::ostream& out);
  void bind(api::Engine& engine) const;
  std::vector<interp::Value> call(api::Engine& engine, const std::string& name);
  std::vector<double> step_stats(const std::vector<interp::Value>& results) const;
  void print_sizes(std::ostream& out, int frames) const;
  void check_finite_state(int frame, const std::vector<interp::Value>& results) const;
  // A distributed run: the sets as bind() binds them (the local parts), and the local fields
  // gathered into the whole sets on rank 0 where it reads them.
  std::vector<runtime::Set*> whole_sets() const;
  std::vector<runtime::Set*> local_sets() const;
  void localize();
  void gather(bool last) const;
  // A distributed run on several ranks: the frames as pieces joined by a .pvtu.
  void start_pieces();
  void write_pieces(int frame, bool last);

  const SceneFile& file_;
  const SceneOptions& options_;
  MeshCache& meshes_;
  Reorder reorder_;
  interp::Trap* trap_;
  BoundSets sets_;
  // A distributed run: this rank's part of each of sets_.sets, in the same order.
  std::vector<std::unique_ptr<runtime::Set>> local_;
  std::map<std::string, SceneTensor> tensors_;
  OutputSeries output_;
  std::optional<PieceSeries> pieces_;  // a distributed run's piece of each frame
  // --jit-stats without a debugger's trap: Ctrl-C stops the run through this one.
  mutable interp::Trap own_trap_;
  // Declared after the sets and tensors it is bound to: destroyed before them.
  std::unique_ptr<api::Engine> engine_;
  bool jit_stats_printed_ = false;
  int last_written_ = -1;  // the last frame written to the series
};

}  // namespace simit::scene
