// `mpirun -np K simit run --distributed SCENE.toml`: the scene run on every rank over its part
// of the sets (scene/distributed.h); rank 0 prints and writes, and one rank's failure ends all.
#include <ostream>
#include <streambuf>

#include "simit/commands.h"
#include "simit/scene.h"

#ifdef SIMIT_HAVE_MPI
#include "dist/mpi/comm.h"
#include "dist/mpi/scene_distribution.h"
#include "scene/distributed.h"
#endif

namespace simit::tools {

namespace {

// Where the ranks other than 0 print: nowhere (their progress and sizes would repeat rank 0's).
class NullBuffer : public std::streambuf {
 protected:
  int overflow(int c) override { return traits_type::not_eof(c); }
};

}  // namespace

int run_distributed_scene(scene::SceneOptions options, std::ostream& out, std::ostream& err) {
#ifndef SIMIT_HAVE_MPI
  (void)options;
  (void)out;
  err << "simit: error: --distributed needs MPI, and this simit was built without it "
         "(install libopenmpi-dev and rebuild)\n";
  return 1;
#else
  // Said before MPI starts, once (the scene file's own `executor` key is checked by the scene).
  if (options.executor_given && options.executor.kind == ExecutorKind::Gpu) {
    err << "simit: error: --distributed runs the interpreter or the JIT (--executor gpu is not "
           "distributed yet)\n";
    return 1;
  }
  std::shared_ptr<scene::Distributed> ranks;
  try {
    ranks = dist::mpi::start_scene_distribution();
  } catch (const std::exception& e) {
    err << "simit: error: --distributed: " << e.what() << "\n";
    return 1;
  }
  options.distributed = ranks;
  const int rank = ranks->rank();
  NullBuffer nothing;
  std::ostream quiet(&nothing);
  if (rank != 0) {
    // Rank 0 writes the output and prints; the others compute their parts only.
    options.quiet = true;
    options.progress_line = false;
    options.final_csv.clear();
    options.png.clear();
  }
  std::ostream& where = rank == 0 ? out : quiet;
  // Opening the scene (reading it, compiling its program) fails alike on every rank: rank 0
  // reports it, the others wait for its abort.
  std::unique_ptr<scene::Scene> opened = scene::Scene::open(options, rank == 0 ? err : quiet);
  if (!opened) {
    if (rank != 0) ranks->wait_for_abort();
    err.flush();
    ranks->abort(1);
  }
  const int status = opened->run(where, err);
  if (status != 0) {
    // The others may be waiting for this rank in a collective step: end them all, after the
    // error (already on `err`), the rank that met it, and whatever was written completely.
    err << "simit: rank " << rank << " of " << ranks->ranks()
        << " stopped the run; every rank ends with it\n";
    err.flush();
    where.flush();
    ranks->abort(status);
  }
  return status;
#endif
}

}  // namespace simit::tools
