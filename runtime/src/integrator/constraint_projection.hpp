#pragma once
// constraint_projection.hpp (internal): the factor of Φ_q W Φ_qᵀ (m x m, W diagonal and positive), with which the
// stabilised index-2 form moves the positions back onto Φ = 0 (generalized_alpha_newton.cpp). Dense Cholesky for a few
// bodies; for many, a sparse Cholesky: rows k and l couple only when they share a body, so the matrix has
// O(m) entries, and its fill-reducing ordering (AMD) is computed once per pattern and kept. The product is summed
// body by body: the rows that touch a body's columns form a small dense block J_b (a revolute-jointed GCMS body:
// 19 rows x 66 columns), J_b W_b J_bᵀ is one dense product, and its lower triangle is added along a plan made once
// per Jacobian pattern. Eigen's general sparse product and its conversions took four fifths of the factorization's
// time on a chain of 64 rigid links (perf); a plan over the Jacobian's pairs of entries column by column, the
// previous way, did 12 500 scattered products per GCMS body where the dense block does the same flops in cache.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <utility>
#include <vector>

namespace flexbody::runtime::detail {

class ConstraintProjection {
 public:
  /// `bodies`: the first column of each body's coordinates and, last, the column count (System::offset); used by
  /// the sparse form.
  ConstraintProjection(bool sparse, std::vector<Eigen::Index> bodies) : sparse_(sparse), bodies_(std::move(bodies)) {}
  /// Factorizes Φ_q W Φ_qᵀ for the Jacobian J (m x n) and W = diag(weights); false if it is not positive definite
  /// (dependent rows).
  bool factor(const Eigen::SparseMatrix<double>& jacobian, const Eigen::VectorXd& weights);
  /// x ← (Φ_q W Φ_qᵀ)⁻¹ x.
  void solve_in_place(Eigen::VectorXd& x);

 private:
  /// Makes product_'s pattern (the lower triangle of Φ_q Φ_qᵀ's), each body's rows and each entry's row in its
  /// body's block, and plan_, for the Jacobian's pattern.
  void plan(const Eigen::SparseMatrix<double>& jacobian);

  bool sparse_;
  std::vector<Eigen::Index> bodies_;
  Eigen::LLT<Eigen::MatrixXd> dense_;
  Eigen::SparseMatrix<double> product_;  ///< the lower triangle of Φ_q W Φ_qᵀ
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor_;
  Eigen::VectorXi outer_, inner_;  ///< the Jacobian's pattern that the plan and factor_ were made for
  std::vector<int> block_rows_;    ///< per body b, its rows (sorted) from block_start_[b]
  std::vector<int> block_start_;   ///< per body, where its rows start in block_rows_ (and, last, their end)
  std::vector<int> local_row_;     ///< per Jacobian entry: its row's index in its body's block
  /// Per body, per pair (i ≥ j) of its block's rows, column by column of the lower triangle: the index of entry
  /// (row i, row j) in product_'s values.
  std::vector<int> plan_;
  Eigen::MatrixXd block_, weighted_, gram_;  ///< work: J_b, J_b W_b and J_b W_b J_bᵀ (at the largest body's size)
  Eigen::VectorXd work_;
};

}  // namespace flexbody::runtime::detail
