// The work behind the `simit` subcommands that need the compiler's internals: `simit check`
// (diagnostics and tree dumps), `simit run FILE --call` (one function, literal arguments) and
// `simit partition` (a mesh cut into parts).
// The command line (tools/) parses arguments and calls these.
#pragma once

#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "simit/executor.h"
#include "simit/scene.h"

namespace simit::tools {

struct CheckOptions {
  std::vector<std::string> files;
  std::vector<std::string> dumps;  // "ast" and/or "typed", printed to `out` in that order
};

// Checks every file; diagnostics go to `err`. Returns 0 when all are clean, else 1.
int run_check(const CheckOptions& options, std::ostream& out, std::ostream& err);

// `simit run FILE --call NAME [ARGS...]`: runs one exported function that needs no sets.
struct RunOptions {
  std::string file;
  std::string func;
  std::vector<std::string> args;  // one literal per parameter, e.g. `2.5`, `[1.0, 2.0]'`
  bool float32 = false;
  bool check_finite = false;
  // What runs the function (`--executor`, `--jit-threshold`, `--check-jit`, `--dump`,
  // `--jit-cache`), as parsed from the command line; dumps print to `out`.
  ExecutorChoice executor;
  bool jit_stats = false;  // jit: print each trace's figures after the run
};

// Prints what the program prints, then one `name = literal` line per result, to `out`.
// Returns 0, or 1 (with diagnostics or the run-time error on `err`) when the file does not
// compile, the arguments do not fit, or the run stops with a run-time error.
int run_function(const RunOptions& options, std::ostream& out, std::ostream& err);

// `simit partition MESH --parts K,...`: the mesh's vertex graph (every element's vertices
// adjacent) cut into each K parts (METIS, dist/partition.h), one line per K: cut edges,
// balance, ghosts (vertices a part's elements reach that another part owns) and neighbours
// (parts a part exchanges with). Returns 0, or 1 with the error on `err` (a mesh that does
// not read, more parts than vertices, a build without METIS).
struct PartitionOptions {
  std::string mesh;
  std::vector<int> parts;
  bool csv = false;  // comma-separated lines instead of the table
  // How the vertices are renumbered before the cut, as a scene's `reorder` key does it:
  // "rcm" (a scene's default), "hilbert" or "off".
  std::string reorder = "rcm";
};
int run_partition(const PartitionOptions& options, std::ostream& out, std::ostream& err);

// `simit run --distributed SCENE.toml` under mpirun: each rank runs the scene over its part of
// the sets, rank 0 prints and writes the output; a failure on any rank ends them all with its
// message (MPI_Abort). Returns 1 with the reason when this simit has no MPI.
int run_distributed_scene(scene::SceneOptions options, std::ostream& out, std::ostream& err);

// Runs `command` and returns its exit status; an exception escaping it is simit's own bug,
// reported on `err` as such (an internal assertion with its place, or any other exception)
// with exit status 3, never as a crash or as the user's error.
int run_guarded(const std::function<int()>& command, std::ostream& err);

}  // namespace simit::tools
