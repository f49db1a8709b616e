#pragma once
// constraint_projection.hpp (internal): the factor of Φ_q W Φ_qᵀ (m x m, W diagonal and positive), with which the
// stabilised index-2 form moves the positions back onto Φ = 0 (generalized_alpha.cpp). Dense Cholesky for a few
// bodies; for many, a sparse Cholesky: rows k and l couple only when they share a body, so the matrix has
// O(m) entries, and its fill-reducing ordering (AMD) is computed once per pattern and kept. The sparse product's
// lower triangle is summed along a plan made once per Jacobian pattern (each column's pairs of entries and where
// their product goes): Eigen's general sparse product and its conversions took four fifths of the factorization's
// time on a chain of 64 rigid links (perf).

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <vector>

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
  /// Makes product_'s pattern (the lower triangle of Φ_q Φ_qᵀ's) and plan_ for the Jacobian's pattern.
  void plan(const Eigen::SparseMatrix<double>& jacobian);

  bool sparse_;
  Eigen::LLT<Eigen::MatrixXd> dense_;
  Eigen::SparseMatrix<double> product_;  ///< the lower triangle of Φ_q W Φ_qᵀ
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor_;
  Eigen::VectorXi outer_, inner_;  ///< the Jacobian's pattern that plan_ and factor_ were made for
  /// Per column c of the Jacobian, per pair of its entries (p, r) with row(p) ≥ row(r), in loop order: the index of
  /// entry (row(p), row(r)) in product_'s values.
  std::vector<int> plan_;
  Eigen::VectorXd work_;
};

}  // namespace flexbody::runtime::detail
