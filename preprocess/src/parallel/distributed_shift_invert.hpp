#pragma once
// distributed_shift_invert.hpp (internal, SLEPc builds only): K̄ and M̄ distributed by rows over the MPI
// ranks, SLEPc's Krylov-Schur in shift-and-invert on a MUMPS Cholesky factorization of K̄ - sigma M̄, and
// solves with that factor.
//
// Every member function is collective over PETSC_COMM_WORLD: rank 0 calls it from the pipeline (through
// SlepcShiftSolve) after sending the matching Command, the workers from serve(). Arguments marked "rank 0"
// are read on rank 0 only and broadcast; results marked "rank 0" are returned there (empty elsewhere).

#include "flexbody/preprocess/eigensolver.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <slepceps.h>

#include <Eigen/Core>

#include <vector>

namespace flexbody::preprocess::parallel {

/// What a distributed eigen solve returns on rank 0.
struct DistributedEigenPairs {
  Eigen::VectorXd eigenvalues;  ///< ascending
  Eigen::MatrixXd vectors;      ///< n x nev, node-interleaved as K̄'s rows
  int iterations = 0;           ///< Krylov-Schur restarts
  int operator_applies = 0;     ///< solves with the factor
};

class DistributedShiftInvert {
 public:
  /// Rank 0: K̄ (3 n_n, upper triangle), M_s (n_n, upper triangle) and the deflation basis (3 n_n x r,
  /// M̄-orthonormal, r may be 0); other ranks pass null. Each rank receives its block of whole nodes' rows.
  DistributedShiftInvert(const SparseMatrix* stiffness_upper, const SparseMatrix* scalar_mass_upper,
                         const Eigen::MatrixXd* deflation);
  ~DistributedShiftInvert();
  DistributedShiftInvert(const DistributedShiftInvert&) = delete;
  DistributedShiftInvert& operator=(const DistributedShiftInvert&) = delete;

  [[nodiscard]] Eigen::Index rows() const { return rows_; }

  /// sigma (rank 0): sets up the eigensolver for the eigenvalues nearest above sigma and factorizes
  /// K̄ - sigma M̄. Throws if the factorization fails or finds negative pivots (not positive definite).
  void set_shift(double sigma);

  /// The nev eigenpairs nearest above the shift, the deflation space excluded. nev, ncv (basis size),
  /// tolerance, max_restarts and the start vector (length rows()) are read on rank 0.
  [[nodiscard]] DistributedEigenPairs eigenpairs(int nev, int ncv, double tolerance, int max_restarts,
                                                 const Eigen::VectorXd* start);

  /// y = (K̄ - sigma M̄)^-1 x on the factor of set_shift (x and y on rank 0, length rows()).
  void solve(const double* x, double* y);

  /// Statistics of the last factorization (MUMPS's INFOG/RINFOG, summed over the ranks).
  [[nodiscard]] double factor_entries() const { return factor_entries_; }
  [[nodiscard]] double factor_flops() const { return factor_flops_; }
  [[nodiscard]] double factor_megabytes() const { return factor_megabytes_; }
  [[nodiscard]] double factorize_seconds() const { return factorize_seconds_; }
  /// The largest peak resident memory of ranks 1 ... N-1 [MB] when last measured (after the factorization and
  /// after each eigen solve); 0 on one rank.
  [[nodiscard]] double other_ranks_peak_megabytes() const { return other_ranks_peak_megabytes_; }

 private:
  void to_distributed(const double* x, Vec v);    // rank 0's full vector into the distributed v
  void to_root(Vec v, double* x);                 // the distributed v into rank 0's full vector
  void read_factor_statistics();
  void release();  // destroys every PETSc object made so far (collective)
  void measure_other_ranks_memory();

  Eigen::Index rows_ = 0;
  Mat stiffness_ = nullptr, mass_ = nullptr;
  std::vector<Vec> deflation_;
  Vec work_ = nullptr, work_out_ = nullptr, gathered_ = nullptr;  // gathered_: whole vector on rank 0
  VecScatter to_zero_ = nullptr;
  EPS eps_ = nullptr;
  double sigma_ = 0.0;
  double factor_entries_ = 0.0, factor_flops_ = 0.0, factor_megabytes_ = 0.0, factorize_seconds_ = 0.0;
  double other_ranks_peak_megabytes_ = 0.0;
};

}  // namespace flexbody::preprocess::parallel
