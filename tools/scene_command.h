// `simit run SCENE.toml`: the scene library (simit/scene.h) under the names the command line
// uses; the scene format is documented in README.md ("Scenes").
#pragma once

#include "simit/scene.h"

namespace simit::tools {

using SceneOptions = scene::SceneOptions;
// Checks the whole scene (keys, program, meshes, fields, output) before the first frame and
// reports the first problem as `SCENE[:line:col]: error: ...` on `err`. Returns 0 on success,
// 1 on any error (the scene, the program, a mesh, or a run-time error of the program).
using scene::run_scene;

}  // namespace simit::tools
