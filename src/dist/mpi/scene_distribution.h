// A scene run on MPI ranks (scene/distributed.h) over the distributed layer: each vertex set
// cut by the partitioner (dist/partition.h) on rank 0, every rank's part laid out with its
// ghosts (dist/overlap.h), ghosts refreshed and sums added through the communicator.
#pragma once

#include <memory>

#include "scene/distributed.h"

namespace simit::dist::mpi {

// Starts MPI (once per process; it ends when the last reference goes) and returns the scene's
// seam over it. Throws CommError when MPI does not start.
std::shared_ptr<scene::Distributed> start_scene_distribution();

}  // namespace simit::dist::mpi
