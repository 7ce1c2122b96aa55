// The `simit` command line: subcommands and their options.
#pragma once

#include <optional>
#include <ostream>

#include "scene_command.h"
#include "simit/executor.h"

namespace simit::tools {

// Parses the arguments and runs a subcommand. Returns the process exit status: the
// subcommand's, 0 for --help and --version, 2 for a usage error.
int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

// The executor choice the arguments of `simit run` or `simit test` hand to the engine, parsed
// as run_cli parses them, nothing run (tests of the parsing); nullopt after a usage error
// on `err`.
std::optional<ExecutorChoice> parse_executor_choice(int argc, const char* const* argv,
                                                    std::ostream& err);

// The options `simit run SCENE.toml ...` hands to the scene, parsed as run_cli parses them,
// nothing read or run (tests of the parsing); nullopt after a usage error on `err` or for
// arguments that are not a scene run.
std::optional<SceneOptions> parse_scene_options(int argc, const char* const* argv,
                                                std::ostream& err);

}  // namespace simit::tools
