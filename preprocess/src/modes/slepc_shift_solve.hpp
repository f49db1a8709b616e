#pragma once
// slepc_shift_solve.hpp (internal, SLEPc builds only): the ShiftSolve of the slepc backend. Rank 0 holds
// this object; each call sends the matching command to the worker ranks and takes part in the collective
// step (parallel/distributed_shift_invert.hpp). The rigid-body deflation P = I - R Rᵀ M̄ of perform_op is
// applied on rank 0; in the eigen solve SLEPc keeps its Krylov basis M̄-orthogonal to R (its deflation space).

#include "flexbody/preprocess/eigensolver.hpp"

#include <memory>

namespace flexbody::preprocess {

namespace parallel {
class DistributedShiftInvert;
}

class SlepcShiftSolve final : public ShiftSolve {
 public:
  /// Starts MPI and SLEPc as a single process if fbprep was not launched by mpirun.
  SlepcShiftSolve(const SparseMatrix& stiffness_upper, const SparseMatrix& scalar_mass_upper, Eigen::MatrixXd deflation);
  SlepcShiftSolve(SparseMatrix&&, const SparseMatrix&, Eigen::MatrixXd) = delete;  // borrows K and M_s
  SlepcShiftSolve(const SparseMatrix&, SparseMatrix&&, Eigen::MatrixXd) = delete;
  ~SlepcShiftSolve() override;

  [[nodiscard]] Eigen::Index rows() const override { return rows_; }
  void set_shift(double sigma) override;
  void perform_op(const double* x, double* y) override;
  /// The nev eigenpairs nearest above the shift by Krylov-Schur, M̄-normalized, ascending.
  [[nodiscard]] EigenPairs eigenpairs(const VectorMassOperator& mass, int nev, const EigensolverOptions& options);

 private:
  Eigen::Index rows_ = 0;
  Eigen::MatrixXd deflation_, mass_deflation_;  // R and M̄ R
  std::unique_ptr<parallel::DistributedShiftInvert> system_;
};

}  // namespace flexbody::preprocess
