#include "constraint_projection.hpp"

#include <algorithm>

namespace flexbody::runtime::detail {

void ConstraintProjection::plan(const Eigen::SparseMatrix<double>& jacobian) {
  const Eigen::Index m = jacobian.rows();
  const int* outer = jacobian.outerIndexPtr();
  const int* inner = jacobian.innerIndexPtr();
  // The product's entries, column by column of Φ_q: (row(p), row(r)) for each pair with row(p) ≥ row(r).
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index c = 0; c < jacobian.cols(); ++c)
    for (int p = outer[c]; p < outer[c + 1]; ++p)
      for (int r = outer[c]; r < outer[c + 1]; ++r)
        if (inner[p] >= inner[r]) entries.emplace_back(inner[p], inner[r], 0.0);
  product_.resize(m, m);
  product_.setFromTriplets(entries.begin(), entries.end());  // each position once, rows sorted in each column
  product_.makeCompressed();
  const int* p_outer = product_.outerIndexPtr();
  const int* p_inner = product_.innerIndexPtr();
  plan_.clear();
  plan_.reserve(entries.size());
  for (Eigen::Index c = 0; c < jacobian.cols(); ++c)
    for (int p = outer[c]; p < outer[c + 1]; ++p)
      for (int r = outer[c]; r < outer[c + 1]; ++r) {
        if (inner[p] < inner[r]) continue;
        const int* first = p_inner + p_outer[inner[r]];  // entry (row(p), row(r)) is in column row(r)
        const int* last = p_inner + p_outer[inner[r] + 1];
        plan_.push_back(static_cast<int>(std::lower_bound(first, last, inner[p]) - p_inner));
      }
  outer_ = Eigen::Map<const Eigen::VectorXi>(outer, jacobian.cols() + 1);
  inner_ = Eigen::Map<const Eigen::VectorXi>(inner, jacobian.nonZeros());
  factor_.analyzePattern(product_);  // AMD ordering and the elimination tree: once per pattern
}

bool ConstraintProjection::factor(const Eigen::SparseMatrix<double>& jacobian, const Eigen::VectorXd& weights) {
  if (!sparse_) {
    const Eigen::MatrixXd j(jacobian);
    dense_.compute(j * weights.asDiagonal() * j.transpose());
    return dense_.info() == Eigen::Success;
  }
  if (!jacobian.isCompressed()) return factor(Eigen::SparseMatrix<double>(jacobian), weights);  // compressed copy
  const Eigen::Index columns = jacobian.cols(), nonzeros = jacobian.nonZeros();
  const int* outer = jacobian.outerIndexPtr();
  const int* inner = jacobian.innerIndexPtr();
  const bool same = outer_.size() == columns + 1 && inner_.size() == nonzeros &&
                    std::equal(outer_.data(), outer_.data() + columns + 1, outer) &&
                    std::equal(inner_.data(), inner_.data() + nonzeros, inner);
  if (!same) plan(jacobian);
  // Σ_c w_c J(i, c) J(k, c) into entry (i, k), i ≥ k, along the plan.
  double* product = product_.valuePtr();
  std::fill(product, product + product_.nonZeros(), 0.0);
  const double* values = jacobian.valuePtr();
  std::size_t next = 0;
  for (Eigen::Index c = 0; c < columns; ++c)
    for (int p = outer[c]; p < outer[c + 1]; ++p) {
      const double weighted = weights(c) * values[p];
      for (int r = outer[c]; r < outer[c + 1]; ++r)
        if (inner[p] >= inner[r]) product[plan_[next++]] += weighted * values[r];
    }
  factor_.factorize(product_);
  return factor_.info() == Eigen::Success;
}

void ConstraintProjection::solve_in_place(Eigen::VectorXd& x) {
  if (sparse_) {
    work_ = x;
    x = factor_.solve(work_);
  }
  else
    dense_.solveInPlace(x);
}

}  // namespace flexbody::runtime::detail
