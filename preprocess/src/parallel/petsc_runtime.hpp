#pragma once
// petsc_runtime.hpp (internal, SLEPc builds only): MPI and SLEPc initialization, PETSc errors as
// exceptions, and the command channel from rank 0 to the worker ranks.
//
// fbprep under `mpirun -np N` is one driver (rank 0 runs the whole pipeline: CAD, mesh, assembly, GCMS,
// output) and N - 1 workers that only take part in the distributed eigen stage. Rank 0 starts each
// collective step by broadcasting a Command; the workers wait for it in serve() (parallel_session.cpp).

#include <petscsys.h>

#include <string>

namespace flexbody::preprocess::parallel {

/// True when MPI_Init has to happen at program start: the process was started by mpirun/mpiexec (Open MPI,
/// MPICH's Hydra or a PMIx launcher set these variables).
[[nodiscard]] bool launched_by_mpi_launcher();

/// Initializes MPI and SLEPc once per process (later calls do nothing). Without a launcher MPI starts as a
/// single process ("singleton"). PETSc's options come from the PETSC_OPTIONS environment variable only, so
/// fbprep's own command line is never read as PETSc options. PETSc errors are returned, not printed.
void initialize();
[[nodiscard]] bool initialized();
/// SlepcFinalize (which finalizes MPI). Call once, after every PETSc object is destroyed.
void finalize();

/// Rank and size of PETSC_COMM_WORLD; 0 and 1 before initialize().
[[nodiscard]] int rank();
[[nodiscard]] int size();

/// Throws std::runtime_error("<what>: <PETSc's message>") unless code is 0.
void check(PetscErrorCode code, const char* what);

/// The collective steps rank 0 asks the workers to take part in.
enum class Command : int { stop = 0, create = 1, set_shift = 2, eigenpairs = 3, solve = 4, destroy = 5 };
/// Rank 0: tells every worker which step comes next.
void send_command(Command command);
/// Workers: waits for rank 0's next command, sleeping between polls so an idle worker does not take a
/// core from rank 0 (a blocking MPI_Bcast busy-waits).
[[nodiscard]] Command receive_command();

/// Runs `step` on every rank, then agrees on the outcome: if any rank threw, every rank throws
/// std::runtime_error with the message of the lowest failing rank. `step` must fail collectively or
/// before its first communication (a rank that fails inside a collective call of PETSc leaves the
/// others waiting, as in any MPI program).
template <typename Step>
void collective(Step&& step);

/// Implementation of collective(): the agreement after a step that failed locally with `error` (empty: it
/// did not).
void agree(const std::string& error);

template <typename Step>
void collective(Step&& step) {
  std::string error;
  try {
    step();
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "unknown error";
  }
  agree(error);
}

}  // namespace flexbody::preprocess::parallel
