// `simit run SCENE.toml`: a simulation described by a scene file (program, sets bound to mesh
// files, field initialisation, init and step procedures, frames, ParaView output). The scene
// format is documented in README.md ("Scenes").
#pragma once

#include <ostream>
#include <string>

namespace simit::tools {

struct SceneOptions {
  std::string file;        // the .toml scene
  int frames = -1;         // overrides the scene's `frames` when >= 0
  std::string output_dir;  // overrides [output] folder when not empty
  std::string final_csv;   // when set: the last frame's positions as "x,y,z" lines
  bool float32 = false;
  bool check_finite = false;
  bool progress_line = false;  // rewrite one progress line (a terminal) instead of plain lines
};

// Checks the whole scene (keys, program, meshes, fields, output) before the first frame and
// reports the first problem as `SCENE[:line:col]: error: ...` on `err`. Returns 0 on success,
// 1 on any error (the scene, the program, a mesh, or a run-time error of the program).
int run_scene(const SceneOptions& options, std::ostream& out, std::ostream& err);

}  // namespace simit::tools
