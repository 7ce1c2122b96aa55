// The REPL's reader of scene files (`:scene`): the scene library's sets and tensors as the
// session binds them.
#pragma once

#include <optional>
#include <ostream>
#include <string>

#include "scene_data.h"

namespace simit::repl {

// A SceneLoader: reads and builds the scene (runs nothing); reports a problem on `err` as
// `simit run` would and returns nothing.
std::optional<SceneData> load_scene(const std::string& path, bool float32, std::ostream& err);

}  // namespace simit::repl
