// What the REPL and the step debugger reach inside a scene beyond the public API: the compiled
// program, and the sets and tensors built from the meshes before anything runs.
#pragma once

#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "runtime/set.h"
#include "runtime/tensor.h"
#include "simit/scene.h"

namespace simit::frontend::ast {
struct Program;
}
namespace simit::interp {
class Trap;
}

namespace simit::scene {

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

struct SceneAccess {
  // Scene::open, with every run's statements under the trap point switched through `trap`
  // (interp/hook.h: the step debugger).
  static std::unique_ptr<Scene> open(const SceneOptions& options, interp::Trap* trap,
                                     std::ostream& err);
  // The executor the runs use: the options' choice with the scene file's keys applied.
  static const ExecutorChoice& executor(const Scene& scene);
  // The compiled program the runs execute (the debugger resolves breakpoints against it).
  static const frontend::ast::Program& program(const Scene& scene);
  // Builds the sets afresh and reads the tensors, running nothing; nullopt after reporting a
  // problem on `err`.
  static std::optional<SceneSets> build(Scene& scene, std::ostream& err);
};

// The REPL's `:scene`: open, then build (float fields in binary32 when `float32`).
std::optional<SceneSets> load_scene_sets(const std::string& path, bool float32, std::ostream& err);

}  // namespace simit::scene
