// The stabilised form's projection factor (runtime/src/integrator/constraint_projection.hpp): the sparse Φ_q W Φ_qᵀ,
// summed body by body, against the dense one on a random chain-like Jacobian (each row block touching one or two
// bodies, some columns empty), and dependent rows refused.
#include "integrator/constraint_projection.hpp"

#include <Eigen/SparseCore>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <vector>

namespace {

TEST(ConstraintProjection, SparseBodyBlocksMatchTheDenseProduct) {
  std::srand(21);
  const std::vector<Eigen::Index> widths = {12, 30, 7, 12, 21};  // rigid, GCMS, floating-frame sizes
  std::vector<Eigen::Index> bodies = {0};
  for (const Eigen::Index w : widths) bodies.push_back(bodies.back() + w);
  const Eigen::Index n = bodies.back();
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::Index row = 0;
  for (std::size_t b = 0; b < widths.size(); ++b) {
    for (int k = 0; k < 6; ++k, ++row) {  // six rows on body b, and on body b − 1 (a joint), but for the first
      for (Eigen::Index c = bodies[b]; c < bodies[b + 1]; c += 1 + (c % 3 == 0))  // some columns skipped
        entries.emplace_back(row, c, Eigen::internal::random<double>(-1.0, 1.0));
      if (b > 0)
        for (Eigen::Index c = bodies[b - 1]; c < bodies[b - 1] + 5; ++c) entries.emplace_back(row, c, Eigen::internal::random<double>(-1.0, 1.0));
    }
  }
  Eigen::SparseMatrix<double> jacobian(row, n);
  jacobian.setFromTriplets(entries.begin(), entries.end());
  jacobian.makeCompressed();
  const Eigen::VectorXd weights = Eigen::VectorXd::Random(n).cwiseAbs() + Eigen::VectorXd::Constant(n, 0.1);
  flexbody::runtime::detail::ConstraintProjection sparse(true, bodies), dense(false, bodies);
  ASSERT_TRUE(sparse.factor(jacobian, weights));
  ASSERT_TRUE(dense.factor(jacobian, weights));
  for (int pass = 0; pass < 2; ++pass) {  // the second along the kept plan, with new values on the same pattern
    const Eigen::VectorXd rhs = Eigen::VectorXd::Random(row);
    Eigen::VectorXd x_sparse = rhs, x_dense = rhs;
    sparse.solve_in_place(x_sparse);
    dense.solve_in_place(x_dense);
    const Eigen::MatrixXd j(jacobian);
    const Eigen::VectorXd back = j * weights.asDiagonal() * j.transpose() * x_sparse;
    EXPECT_LT((back - rhs).norm(), 1e-10 * rhs.norm());  // cond(Φ_q W Φ_qᵀ) ~ 1e2 here
    EXPECT_LT((x_sparse - x_dense).norm(), 1e-10 * x_dense.norm());
    for (Eigen::Index k = 0; k < jacobian.nonZeros(); ++k) jacobian.valuePtr()[k] *= 1.0 + 0.1 * std::sin(static_cast<double>(k));
    ASSERT_TRUE(sparse.factor(jacobian, weights));
    ASSERT_TRUE(dense.factor(jacobian, weights));
  }
  // A repeated row: not positive definite.
  Eigen::SparseMatrix<double> doubled(row + 1, n);
  std::vector<Eigen::Triplet<double>> more = entries;
  for (const auto& e : entries)
    if (e.row() == 3) more.emplace_back(row, e.col(), e.value());
  doubled.setFromTriplets(more.begin(), more.end());
  doubled.makeCompressed();
  EXPECT_FALSE(sparse.factor(doubled, weights));
}

}  // namespace
