// A scene file read once: the TOML document, its top-level keys checked, and its program
// compiled with the init and step procedures found. Every later step reports its problems
// through fail(), which names the scene file and the TOML node's line and column.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <toml++/toml.h>  // Debian names the header toml.h (upstream also ships toml.hpp)

#include "api/compiled_program.h"
#include "simit/executor.h"

namespace simit::scene {

// A problem with the scene; the message is complete ("FILE:line:col: error: ...").
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// How a scene renumbers each mesh before it builds sets from it (the `reorder` key): not at
// all, vertices by reverse Cuthill-McKee, or vertices along a Hilbert curve; the elements
// then by their smallest new vertex (runtime/mesh/reorder.h, scene/mesh_cache.h).
enum class Reorder { Off, Rcm, Hilbert };
constexpr Reorder kDefaultReorder = Reorder::Rcm;

struct SceneFile {
  std::string path;  // the scene file as given
  std::string dir;   // its folder, against which the paths inside it are resolved
  toml::table doc;
  std::string program_path, init_name, step_name;
  int frames = 0;
  double frame_time = 1.0;
  bool finite_check = true;  // `finite_check = false` lets NaN and infinity through the frames
  Reorder reorder = kDefaultReorder;  // `reorder`
  // `executor`, `threads` and `jit_cache`, when the scene names them (the command line's win).
  std::optional<ExecutorKind> executor;
  std::optional<int> threads;
  std::optional<std::string> jit_cache;
  std::shared_ptr<const api::CompiledProgram> program;
  std::vector<std::string> stat_names;  // the scalar results of step, reported per frame

  [[noreturn]] void fail(const toml::node* at, const std::string& what) const;
  // Every key of `t` must be one of `allowed`.
  void check_keys(const toml::table& t, const std::string& table_name,
                  const std::set<std::string>& allowed) const;
  std::string required_string(const toml::table& t, const std::string& table_name,
                              const std::string& key) const;
  std::optional<std::string> optional_string(const toml::table& t, const std::string& table_name,
                                             const std::string& key) const;
  // A path written in the scene, relative to its folder.
  std::string resolve(const std::string& relative) const;
};

// Parses `path`, checks the top-level keys and compiles the program. Throws SceneError.
std::unique_ptr<SceneFile> read_scene_file(const std::string& path);

// The program's extern declarations of one kind (sets or tensors), by name.
std::map<std::string, const frontend::ast::Variable*> program_externs(const SceneFile& file,
                                                                      bool sets);

}  // namespace simit::scene
