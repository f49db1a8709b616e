#include "constraint_projection.hpp"

#include <algorithm>
#include <stdexcept>

namespace flexbody::runtime::detail {

void ConstraintProjection::plan(const Eigen::SparseMatrix<double>& jacobian) {
  const Eigen::Index m = jacobian.rows();
  const int* outer = jacobian.outerIndexPtr();
  const int* inner = jacobian.innerIndexPtr();
  if (bodies_.empty() || bodies_.back() != jacobian.cols())
    throw std::invalid_argument("ConstraintProjection: the bodies' columns do not cover the Jacobian's");
  const std::size_t n_b = bodies_.size() - 1;
  // Each body's rows: those with an entry in its columns.
  block_rows_.clear();
  block_start_.assign(1, 0);
  local_row_.assign(static_cast<std::size_t>(jacobian.nonZeros()), 0);
  std::vector<Eigen::Triplet<double>> entries;  // the product's lower triangle (a position two bodies share twice)
  for (std::size_t b = 0; b < n_b; ++b) {
    const auto first = static_cast<std::size_t>(block_start_.back());
    for (Eigen::Index c = bodies_[b]; c < bodies_[b + 1]; ++c)
      for (int p = outer[c]; p < outer[c + 1]; ++p) block_rows_.push_back(inner[p]);
    std::sort(block_rows_.begin() + static_cast<std::ptrdiff_t>(first), block_rows_.end());
    block_rows_.erase(std::unique(block_rows_.begin() + static_cast<std::ptrdiff_t>(first), block_rows_.end()), block_rows_.end());
    block_start_.push_back(static_cast<int>(block_rows_.size()));
    const auto begin = block_rows_.begin() + static_cast<std::ptrdiff_t>(first);
    for (Eigen::Index c = bodies_[b]; c < bodies_[b + 1]; ++c)
      for (int p = outer[c]; p < outer[c + 1]; ++p)
        local_row_[static_cast<std::size_t>(p)] = static_cast<int>(std::lower_bound(begin, block_rows_.end(), inner[p]) - begin);
    for (auto j = begin; j != block_rows_.end(); ++j)
      for (auto i = j; i != block_rows_.end(); ++i) entries.emplace_back(*i, *j, 0.0);  // block_rows_ sorted: i ≥ j
  }
  product_.resize(m, m);
  product_.setFromTriplets(entries.begin(), entries.end());  // each position once, rows sorted in each column
  product_.makeCompressed();
  const int* p_outer = product_.outerIndexPtr();
  const int* p_inner = product_.innerIndexPtr();
  plan_.clear();
  for (std::size_t b = 0; b < n_b; ++b) {
    const int* rows = block_rows_.data() + block_start_[b];
    const int count = block_start_[b + 1] - block_start_[b];
    for (int j = 0; j < count; ++j)
      for (int i = j; i < count; ++i) {  // entry (rows[i], rows[j]) is in column rows[j]
        const int* first = p_inner + p_outer[rows[j]];
        plan_.push_back(static_cast<int>(std::lower_bound(first, p_inner + p_outer[rows[j] + 1], rows[i]) - p_inner));
      }
  }
  Eigen::Index rows = 0, width = 0;  // the work blocks at their largest, once per pattern
  for (std::size_t b = 0; b < n_b; ++b) {
    rows = std::max<Eigen::Index>(rows, block_start_[b + 1] - block_start_[b]);
    width = std::max(width, bodies_[b + 1] - bodies_[b]);
  }
  block_.resize(rows, width);
  weighted_.resize(rows, width);
  gram_.resize(rows, rows);
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
  const bool same = outer_.size() == columns + 1 && inner_.size() == nonzeros &&
                    std::equal(outer_.data(), outer_.data() + columns + 1, outer) &&
                    std::equal(inner_.data(), inner_.data() + nonzeros, jacobian.innerIndexPtr());
  if (!same) plan(jacobian);
  // Body by body: J_b W_b J_bᵀ over the body's rows, its lower triangle into the product along the plan.
  double* product = product_.valuePtr();
  std::fill(product, product + product_.nonZeros(), 0.0);
  const double* values = jacobian.valuePtr();
  const int* plan = plan_.data();
  for (std::size_t b = 0; b + 1 < bodies_.size(); ++b) {
    const Eigen::Index count = block_start_[b + 1] - block_start_[b], width = bodies_[b + 1] - bodies_[b];
    if (count == 0) continue;
    auto block = block_.topLeftCorner(count, width);
    auto weighted = weighted_.topLeftCorner(count, width);
    auto gram = gram_.topLeftCorner(count, count);
    block.setZero();
    for (Eigen::Index c = 0; c < width; ++c)
      for (int p = outer[bodies_[b] + c]; p < outer[bodies_[b] + c + 1]; ++p) block(local_row_[static_cast<std::size_t>(p)], c) = values[p];
    weighted.noalias() = block * weights.segment(bodies_[b], width).asDiagonal();
    gram.triangularView<Eigen::Lower>() = weighted * block.transpose();
    for (Eigen::Index j = 0; j < count; ++j)
      for (Eigen::Index i = j; i < count; ++i) product[*plan++] += gram(i, j);
  }
  factor_.factorize(product_);
  return factor_.info() == Eigen::Success;
}

void ConstraintProjection::solve_in_place(Eigen::VectorXd& x) {
  if (!sparse_) {
    dense_.solveInPlace(x);
    return;
  }
  // SimplicialLLT::solve's own steps (P, L, Lᵀ, P⁻¹), with the permutations out of place: its last one, in place,
  // builds a heap mask at every solve.
  if (factor_.permutationP().size() > 0)
    work_.noalias() = factor_.permutationP() * x;
  else
    work_ = x;
  factor_.matrixL().solveInPlace(work_);
  factor_.matrixU().solveInPlace(work_);
  if (factor_.permutationPinv().size() > 0)
    x.noalias() = factor_.permutationPinv() * work_;
  else
    x = work_;
}

}  // namespace flexbody::runtime::detail
