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
//
// RCM is the default. Measured (file order / RCM / Hilbert; simit run --executor jit, frame
// ms the least of 7 runs' medians on a shared 2-core machine, so +-15%):
//   vertex graph bandwidth: bunny 3587 / 713 / 2998, dragon40k 10977 / 467 / 8277,
//     dragon160k 30183 / 888 / 23202, cloth 32x32 33 / 32 / 885;
//   deferred blocks at --threads 2 (tets), then four chunks a thread: fem bunny 42609 /
//     12711 / 8572, dragon40k 132709 / 9089 / 17603, dragon160k 565651 / 48806 / 59705;
//     springs bunny (edges) 24710 / 12417 / 8074; and now, one chunk a thread (chunks of at
//     most 16,384 tets, so dragon160k's are the same): fem bunny 25152 / 1712 / 3030,
//     dragon40k 91388 / 4171 / 8505, springs bunny 14794 / 1739 / 3201;
//   frame ms at --threads 1 and 2: fem bunny 14.3 / 11.4 / 12.1 and 22.3 / 19.4 / 21.7,
//     dragon40k 57.7 / 42.0 / 37.3 and 66.4 / 48.3 / 57.8, dragon160k 308 / 224 / 253 and
//     365 / 226 / 280; springs bunny 8.7 / 8.4 / 9.4 and 15.0 / 13.9 / 12.7; cloth 32x32
//     (generated in grid order already) 14.1 / 15.2 / 12.0 and 25.5 / 25.7 / 29.2.
//   dragon160k's peak RSS (2 frames, 2 threads) 192 -> 167 MB: fewer deferred blocks.
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
