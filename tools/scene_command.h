// `simit run SCENE.toml`: a simulation described by a scene file (program, sets bound to mesh
// files, field initialisation, init and step procedures, frames, ParaView output). The scene
// format is documented in README.md ("Scenes").
#pragma once

#include <optional>
#include <ostream>
#include <string>

#ifdef SIMIT_HAVE_REPL
#include "scene_data.h"
#endif

namespace simit::interp {
class Trap;
}

namespace simit::tools {

struct SceneOptions {
  std::string file;        // the .toml scene
  int frames = -1;         // overrides the scene's `frames` when >= 0
  std::string output_dir;  // overrides [output] folder when not empty
  std::string final_csv;   // when set: the last frame's positions as "x,y,z" lines
  std::string png;         // overrides [output] png when not empty (relative to the current folder)
  bool float32 = false;
  bool check_finite = false;
  bool progress_line = false;  // rewrite one progress line (a terminal) instead of plain lines
  bool load_only = false;      // build the sets but neither create output nor run
  // simit debug: no output files, no timings (its transcript must be reproducible), and the
  // interpreter's trap point switched through this (interp/hook.h).
  bool quiet = false;
  interp::Trap* trap = nullptr;
};

// Checks the whole scene (keys, program, meshes, fields, output) before the first frame and
// reports the first problem as `SCENE[:line:col]: error: ...` on `err`. Returns 0 on success,
// 1 on any error (the scene, the program, a mesh, or a run-time error of the program).
int run_scene(const SceneOptions& options, std::ostream& out, std::ostream& err);

#ifdef SIMIT_HAVE_REPL
// The REPL's scene loader (:scene): the scene read and built, but not run.
std::optional<repl::SceneData> load_scene_data(const std::string& path, bool float32,
                                               std::ostream& err);
#endif

}  // namespace simit::tools
