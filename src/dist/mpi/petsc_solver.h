// Direct solves of a distributed run's system matrices with PETSc (KSP): each rank hands over
// the rows it owns, which the overlap makes complete (dist/overlap.h), and receives the
// solution's owned entries. The system is factored whole on every rank (PCREDUNDANT, PETSc's
// sequential LU), which gives the same bits run after run at the cost of the whole system's
// memory on each rank. Built where PETSc is found (SIMIT_HAVE_PETSC).
#pragma once

#include <span>
#include <string>

#include "dist/mpi/comm.h"
#include "dist/overlap.h"
#include "runtime/system_matrix.h"

namespace simit::dist::mpi {

class PetscSolver {
 public:
  // PETSc starts on the first solve (inside the session's MPI, without its signal handlers,
  // so that Ctrl-C stays the run's) and ends with the solver.
  explicit PetscSolver(const Session& session) : session_(session) {}
  ~PetscSolver();
  PetscSolver(const PetscSolver&) = delete;
  PetscSolver& operator=(const PetscSolver&) = delete;

  // x = A \ b over the ranks: A square, of float blocks, over the set laid out as `rows` with
  // ghost plan `plan` (its rows of owned elements complete); b and x over the same local
  // elements. Writes x's owned entries (its ghosts are the caller's to refresh). Collective.
  // Returns false with the reason in `why` (the same on every rank) when PETSc fails.
  bool solve(const runtime::SystemMatrix& a, const SetPart& rows, const GhostPlan& plan,
             std::span<const double> b, std::span<double> x, std::string& why);

 private:
  const Session& session_;
  bool started_ = false;
};

}  // namespace simit::dist::mpi
