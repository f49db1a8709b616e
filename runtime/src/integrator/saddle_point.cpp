#include "saddle_point.hpp"

namespace flexbody::runtime::detail {

SaddlePointSolver::SaddlePointSolver(const Eigen::SparseMatrix<double>& mass, const Eigen::SparseMatrix<double>& jacobian,
                                     const std::vector<bool>& eliminated) {
  const Eigen::Index n = mass.rows(), m = jacobian.rows();
  std::vector<Eigen::Index> position(static_cast<std::size_t>(n + m));  // K index -> index in F or in y
  for (Eigen::Index i = 0; i < n + m; ++i) {
    const bool in_f = i < n && eliminated[static_cast<std::size_t>(i)];
    std::vector<Eigen::Index>& part = in_f ? f_ : y_;
    position[static_cast<std::size_t>(i)] = static_cast<Eigen::Index>(part.size());
    part.push_back(i);
  }
  const auto is_f = [&](Eigen::Index i) { return i < n && eliminated[static_cast<std::size_t>(i)]; };
  const Eigen::Index n_f = static_cast<Eigen::Index>(f_.size()), n_y = static_cast<Eigen::Index>(y_.size());
  // K's entries sorted into the blocks FF, FR (as its y columns) and RR.
  std::vector<Eigen::Triplet<double>> ff, fr, rr;
  auto add = [&](Eigen::Index i, Eigen::Index j, double value) {
    const Eigen::Index pi = position[static_cast<std::size_t>(i)], pj = position[static_cast<std::size_t>(j)];
    if (is_f(i) && is_f(j)) ff.emplace_back(pi, pj, value);
    else if (is_f(i)) fr.emplace_back(pi, pj, value);
    else if (!is_f(j)) rr.emplace_back(pi, pj, value);  // RF is FRᵀ
  };
  for (Eigen::Index k = 0; k < mass.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(mass, k); it; ++it) add(it.row(), it.col(), it.value());
  for (Eigen::Index k = 0; k < jacobian.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(jacobian, k); it; ++it)
      if (it.value() != 0.0) {
        add(n + it.row(), it.col(), it.value());
        add(it.col(), n + it.row(), it.value());
      }
  Eigen::SparseMatrix<double> reduced(n_y, n_y);
  reduced.setFromTriplets(rr.begin(), rr.end());
  if (n_f > 0) {
    Eigen::SparseMatrix<double> block(n_f, n_f), coupling(n_f, n_y);
    block.setFromTriplets(ff.begin(), ff.end());
    coupling.setFromTriplets(fr.begin(), fr.end());
    block_.compute(block);
    if (block_.info() != Eigen::Success) return;
    std::vector<Eigen::Triplet<double>> kept;
    for (Eigen::Index c = 0; c < n_y; ++c) {
      if (coupling.col(c).nonZeros() == 0) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(coupling, c); it; ++it)
        kept.emplace_back(it.row(), static_cast<Eigen::Index>(coupled_.size()), it.value());
      coupled_.push_back(c);
    }
    const Eigen::Index n_c = static_cast<Eigen::Index>(coupled_.size());
    coupling_.resize(n_f, n_c);
    coupling_.setFromTriplets(kept.begin(), kept.end());
    solved_coupling_ = block_.solve(Eigen::MatrixXd(coupling_));
    const Eigen::MatrixXd correction = Eigen::MatrixXd(coupling_.transpose()) * solved_coupling_;  // K_RF M_FF⁻¹ K_FR
    std::vector<Eigen::Triplet<double>> update;
    update.reserve(static_cast<std::size_t>(n_c * n_c));
    for (Eigen::Index a = 0; a < n_c; ++a)
      for (Eigen::Index b = 0; b < n_c; ++b) update.emplace_back(coupled_[static_cast<std::size_t>(a)],
                                                                 coupled_[static_cast<std::size_t>(b)], -correction(a, b));
    Eigen::SparseMatrix<double> lowered(n_y, n_y);
    lowered.setFromTriplets(update.begin(), update.end());
    reduced += lowered;
  }
  reduced.makeCompressed();
  reduced_.compute(reduced);
  ok_ = reduced_.info() == Eigen::Success;
}

Eigen::VectorXd SaddlePointSolver::solve(const Eigen::VectorXd& rhs) const {
  const Eigen::Index n_f = static_cast<Eigen::Index>(f_.size()), n_y = static_cast<Eigen::Index>(y_.size());
  Eigen::VectorXd r_f(n_f), r_y(n_y);
  for (Eigen::Index i = 0; i < n_f; ++i) r_f(i) = rhs(f_[static_cast<std::size_t>(i)]);
  for (Eigen::Index i = 0; i < n_y; ++i) r_y(i) = rhs(y_[static_cast<std::size_t>(i)]);
  Eigen::VectorXd free_f;
  if (n_f > 0) {
    free_f = block_.solve(r_f);  // M_FF⁻¹ r_F
    const Eigen::VectorXd lowered = coupling_.transpose() * free_f;
    for (std::size_t c = 0; c < coupled_.size(); ++c) r_y(coupled_[c]) -= lowered(static_cast<Eigen::Index>(c));
  }
  const Eigen::VectorXd y = reduced_.solve(r_y);
  Eigen::VectorXd out(rhs.size());
  for (Eigen::Index i = 0; i < n_y; ++i) out(y_[static_cast<std::size_t>(i)]) = y(i);
  if (n_f > 0) {
    Eigen::VectorXd y_c(static_cast<Eigen::Index>(coupled_.size()));
    for (std::size_t c = 0; c < coupled_.size(); ++c) y_c(static_cast<Eigen::Index>(c)) = y(coupled_[c]);
    const Eigen::VectorXd x_f = free_f - solved_coupling_ * y_c;
    for (Eigen::Index i = 0; i < n_f; ++i) out(f_[static_cast<std::size_t>(i)]) = x_f(i);
  }
  return out;
}

}  // namespace flexbody::runtime::detail
