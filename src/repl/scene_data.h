// What `:scene FILE.toml` gives the REPL: the scene's program, its sets built from meshes with
// their fields initialised, and its extern tensors. A loader supplies them (load_scene, or a
// test's own); the REPL binds these to every run.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "interp/value.h"
#include "runtime/set.h"

namespace simit::repl {

struct SceneData {
  std::string path;          // the scene file
  std::string program_path;  // the program it names
  std::string init, step;    // its procedures (init may be empty)
  // Extern sets by name, in the scene's order; owned by `owner`.
  std::vector<std::pair<std::string, runtime::Set*>> sets;
  // Extern tensors by name; the REPL keeps the values the program writes back into them.
  std::vector<std::pair<std::string, interp::Value>> tensors;
  std::shared_ptr<void> owner;
};

// Reads a scene (float fields in binary32 when `float32`); on failure reports on `err` (as
// `simit run` would) and returns nothing.
using SceneLoader = std::function<std::optional<SceneData>(const std::string& path, bool float32,
                                                           std::ostream& err)>;

}  // namespace simit::repl
