#include "constraint_projection.hpp"

#include <algorithm>

namespace flexbody::runtime::detail {

bool ConstraintProjection::factor(const Eigen::SparseMatrix<double>& jacobian, const Eigen::VectorXd& weights) {
  if (!sparse_) {
    const Eigen::MatrixXd j(jacobian);
    dense_.compute(j * weights.asDiagonal() * j.transpose());
    return dense_.info() == Eigen::Success;
  }
  const Eigen::SparseMatrix<double> weighted = jacobian * weights.asDiagonal();
  product_ = weighted * jacobian.transpose();  // structural: the pattern is the Jacobian's, a zero kept as an entry
  product_.makeCompressed();
  const Eigen::Index n = product_.rows(), nonzeros = product_.nonZeros();
  const bool same = outer_.size() == n + 1 && inner_.size() == nonzeros &&
                    std::equal(outer_.data(), outer_.data() + n + 1, product_.outerIndexPtr()) &&
                    std::equal(inner_.data(), inner_.data() + nonzeros, product_.innerIndexPtr());
  if (!same) {  // AMD ordering and the elimination tree: once per pattern
    factor_.analyzePattern(product_);
    outer_ = Eigen::Map<const Eigen::VectorXi>(product_.outerIndexPtr(), n + 1);
    inner_ = Eigen::Map<const Eigen::VectorXi>(product_.innerIndexPtr(), nonzeros);
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
