#pragma once
// flexbody/preprocess/parallel_session.hpp: fbprep under MPI.
//
// `mpirun -np N fbprep ... --eigensolver slepc` runs rank 0 as the driver (the whole pipeline: CAD, mesh,
// assembly, GCMS constants, output) and ranks 1 ... N-1 as workers that hold a block of K̄'s and M̄'s rows
// and take part in the distributed eigen stage: MUMPS factorization and solves, SLEPc's Krylov-Schur.
// A program that links flexbody::preprocess and may run under mpirun creates one ParallelSession at the
// start of main() and lets the workers serve():
//
//   flexbody::preprocess::ParallelSession session;
//   if (session.is_worker()) return session.serve();
//   ... rank 0's program ...
//
// In builds without SLEPc the session refuses a launch with more than one rank (each would run the whole
// pipeline and write the same files).

namespace flexbody::preprocess {

class ParallelSession {
 public:
  /// In SLEPc builds started by mpirun: starts MPI and SLEPc. Otherwise nothing starts here (the slepc backend
  /// starts MPI as a single process when it is first used). Throws std::runtime_error on rank 0 when a
  /// build without SLEPc is launched on more than one rank.
  ParallelSession();
  /// Rank 0: tells the workers to stop; then finalizes SLEPc and MPI if they were started.
  ~ParallelSession();
  ParallelSession(const ParallelSession&) = delete;
  ParallelSession& operator=(const ParallelSession&) = delete;

  [[nodiscard]] int rank() const { return rank_; }
  [[nodiscard]] int ranks() const { return ranks_; }
  [[nodiscard]] bool is_worker() const { return rank_ != 0; }
  /// Workers: takes part in rank 0's distributed steps until rank 0's session ends. Returns the exit code
  /// (0; 1 in a build without SLEPc, whose workers do nothing).
  [[nodiscard]] int serve();

 private:
  int rank_ = 0;
  int ranks_ = 1;
};

/// MPI ranks of this run: 1 unless started under mpirun in a SLEPc build.
[[nodiscard]] int parallel_ranks();

}  // namespace flexbody::preprocess
