#pragma once
// constraint_projection.hpp (internal): the factor of Φ_q W Φ_qᵀ (m x m, W diagonal and positive), with which the
// stabilised index-2 form moves the positions back onto Φ = 0 (generalized_alpha.cpp). Dense Cholesky for a few
// bodies; for many, a sparse Cholesky: rows k and l couple only when they share a body, so the matrix has
// O(m) entries, and its fill-reducing ordering (AMD) is computed once per pattern and kept.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

namespace flexbody::runtime::detail {

class ConstraintProjection {
 public:
  explicit ConstraintProjection(bool sparse) : sparse_(sparse) {}
  /// Factorizes Φ_q W Φ_qᵀ for the Jacobian J (m x n) and W = diag(weights); false if it is not positive definite
  /// (dependent rows).
  bool factor(const Eigen::SparseMatrix<double>& jacobian, const Eigen::VectorXd& weights);
  /// x ← (Φ_q W Φ_qᵀ)⁻¹ x.
  void solve_in_place(Eigen::VectorXd& x);

 private:
  bool sparse_;
  Eigen::LLT<Eigen::MatrixXd> dense_;
  Eigen::SparseMatrix<double> product_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> factor_;
  Eigen::VectorXi outer_, inner_;  ///< the pattern factor_ was analysed for
  Eigen::VectorXd work_;
};

}  // namespace flexbody::runtime::detail
