// A distributed run's direct solves with PETSc (dist/mpi/petsc_solver.h).
#include "dist/mpi/petsc_solver.h"

#include <petscksp.h>

#include <algorithm>
#include <cstring>
#include <vector>

namespace simit::dist::mpi {

namespace {

// PETSc's error code as text.
std::string petsc_error(PetscErrorCode code) {
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  return text ? text : "PETSc error " + std::to_string(static_cast<int>(code));
}

}  // namespace

PetscSolver::~PetscSolver() {
  if (started_) PetscFinalize();
}

bool PetscSolver::solve(const runtime::SystemMatrix& a, const SetPart& rows, const GhostPlan& plan,
                        std::span<const double> b, std::span<double> x, std::string& why) {
  if (!started_) {
    // PETSc inside the run's MPI (it leaves MPI_Finalize to the session), without its signal
    // handlers.
    static char name[] = "simit", option[] = "-no_signal_handler";
    static char* arguments[] = {name, option, nullptr};
    int count = 2;
    char** argv = arguments;
    if (PetscErrorCode e = PetscInitialize(&count, &argv, nullptr, nullptr)) {
      why = "PETSc did not start: " + petsc_error(e);
      return false;
    }
    started_ = true;
  }
  const int bs = a.block_rows();
  const auto local = static_cast<int64_t>(rows.global.size());
  const auto owned = static_cast<int64_t>(rows.owned.size());
  if (!a.is_float() || bs != a.block_cols() || a.rows() != local || a.cols() != local ||
      static_cast<int64_t>(b.size()) != local * bs || x.size() != b.size()) {
    why = "the matrix and vectors do not match the set's part";
    return false;
  }
  // The PETSc number of each local element: the owned ones from this rank's first, in order,
  // the ghosts' from their owners.
  const int64_t first = session_.sum_below(owned);
  std::vector<int32_t> number(static_cast<size_t>(local), -1);
  std::vector<uint8_t> mine(static_cast<size_t>(local), 0);
  for (int64_t n = 0; n < owned; ++n) {
    const auto i = static_cast<size_t>(rows.owned[static_cast<size_t>(n)]);
    number[i] = static_cast<int32_t>(first + n);
    mine[i] = 1;
  }
  session_.refresh_ghosts(plan, std::as_writable_bytes(std::span<int32_t>(number)),
                          sizeof(int32_t));

  const std::vector<int32_t>& row_ptr = a.pattern().row_ptr();
  const std::vector<int32_t>& col_idx = a.pattern().col_idx();
  std::vector<PetscInt> diagonal(static_cast<size_t>(owned)), off(static_cast<size_t>(owned));
  for (int64_t n = 0; n < owned; ++n) {
    const auto i = static_cast<size_t>(rows.owned[static_cast<size_t>(n)]);
    for (int32_t k = row_ptr[i]; k < row_ptr[i + 1]; ++k)
      ++(mine[static_cast<size_t>(col_idx[static_cast<size_t>(k)])] ? diagonal
                                                                    : off)[static_cast<size_t>(n)];
  }

  Mat m = nullptr;
  Vec vb = nullptr, vx = nullptr;
  KSP ksp = nullptr;
  PetscErrorCode e = 0;
  auto step = [&](PetscErrorCode code) {
    if (!e) e = code;
    return !e;
  };
  const auto n = static_cast<PetscInt>(owned * bs);
  step(MatCreate(PETSC_COMM_WORLD, &m)) &&
      step(MatSetSizes(m, n, n, PETSC_DETERMINE, PETSC_DETERMINE)) && step(MatSetType(m, MATAIJ)) &&
      step(MatSetBlockSize(m, bs)) &&
      step(MatXAIJSetPreallocation(m, bs, diagonal.data(), off.data(), nullptr, nullptr)) &&
      step(MatSetOption(m, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  for (int64_t n = 0; n < owned && !e; ++n) {
    const auto i = static_cast<size_t>(rows.owned[static_cast<size_t>(n)]);
    const PetscInt row = number[i];
    for (int32_t k = row_ptr[i]; k < row_ptr[i + 1] && !e; ++k) {
      // A block of zeros stays out: the factorisation's ordering follows the nonzeros, so that
      // an executor that stores more zero blocks than another still gets the same solution.
      const double* block = a.block(k);
      if (std::all_of(block, block + a.block_size(), [](double v) { return v == 0.0; })) continue;
      const PetscInt col = number[static_cast<size_t>(col_idx[static_cast<size_t>(k)])];
      step(MatSetValuesBlocked(m, 1, &row, 1, &col, block, INSERT_VALUES));
    }
  }
  step(MatAssemblyBegin(m, MAT_FINAL_ASSEMBLY)) && step(MatAssemblyEnd(m, MAT_FINAL_ASSEMBLY)) &&
      step(VecCreateMPI(PETSC_COMM_WORLD, n, PETSC_DETERMINE, &vb)) && step(VecDuplicate(vb, &vx));
  if (!e) {
    PetscScalar* p = nullptr;
    if (step(VecGetArray(vb, &p))) {
      for (int64_t r = 0; r < owned; ++r)
        std::memcpy(p + r * bs,
                    b.data() + static_cast<size_t>(rows.owned[static_cast<size_t>(r)]) * bs,
                    static_cast<size_t>(bs) * sizeof(double));
      step(VecRestoreArray(vb, &p));
    }
  }
  // Every rank factors the whole system with PETSc's own sequential LU (PCREDUNDANT): the same
  // bits run after run. MUMPS's parallel LU scales further, but the order in which it adds
  // its ranks' contributions follows their messages' arrival, so its bits vary from run to run.
  PC pc = nullptr, inner_pc = nullptr;
  KSP inner = nullptr;
  step(KSPCreate(PETSC_COMM_WORLD, &ksp)) && step(KSPSetOperators(ksp, m, m)) &&
      step(KSPSetType(ksp, KSPPREONLY)) && step(KSPGetPC(ksp, &pc)) &&
      step(PCSetType(pc, PCREDUNDANT)) && step(PCRedundantGetKSP(pc, &inner)) &&
      step(KSPGetPC(inner, &inner_pc)) && step(PCSetType(inner_pc, PCLU)) &&
      step(PCFactorSetMatSolverType(inner_pc, MATSOLVERPETSC)) && step(KSPSolve(ksp, vb, vx));
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  if (!e && step(KSPGetConvergedReason(ksp, &reason)) && reason < 0)
    why = std::string("PETSc's solve did not converge: ") + KSPConvergedReasons[reason];
  if (!e && reason >= 0) {
    const PetscScalar* p = nullptr;
    if (step(VecGetArrayRead(vx, &p))) {
      for (int64_t r = 0; r < owned; ++r)
        std::memcpy(x.data() + static_cast<size_t>(rows.owned[static_cast<size_t>(r)]) * bs,
                    p + r * bs, static_cast<size_t>(bs) * sizeof(double));
      step(VecRestoreArrayRead(vx, &p));
    }
  }
  if (e) why = "PETSc: " + petsc_error(e);
  KSPDestroy(&ksp);
  VecDestroy(&vx);
  VecDestroy(&vb);
  MatDestroy(&m);
  return why.empty();
}

}  // namespace simit::dist::mpi
