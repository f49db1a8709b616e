#include "flexbody/runtime/reference_constraints.hpp"

#include "../kernels/outer_sum.hpp"
#include "../kernels/rotation.hpp"

#include <Eigen/Geometry>

#include <array>
#include <stdexcept>
#include <string>
#include <utility>

namespace flexbody::runtime {
namespace {

constexpr std::array<std::pair<int, int>, kOrthogonalityRows> kPairs = {
    std::pair{0, 0}, std::pair{1, 1}, std::pair{2, 2}, std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}};

using detail::skew;

void check_tisserand_sizes(const TisserandMatrix& g, const VectorRef& xi) {
  if (xi.size() != 3 * g.cols())
    throw std::invalid_argument("reference constraints: xi has " + std::to_string(xi.size()) + " entries for " +
                                std::to_string(g.cols()) + " fields (expected 3 n_f)");
}

}  // namespace

Eigen::Matrix<double, 9, 1> reference_residual(const TisserandMatrix& g, const Eigen::Matrix3d& a,
                                               const VectorRef& xi) {
  check_tisserand_sizes(g, xi);
  Eigen::Matrix<double, 9, 1> phi;
  for (int k = 0; k < kOrthogonalityRows; ++k) {
    const auto [i, j] = kPairs[static_cast<std::size_t>(k)];
    phi(k) = a.col(i).dot(a.col(j)) - (i == j ? 1.0 : 0.0);  // Eq. 79
  }
  // Eq. 78: Σ_f g_f × ξ̄_f with ξ̄_f = Aᵀ ξ_f. A sum of cross products is the axial vector of the 3 x 3 matrix
  // P = Σ_f g_f ξ̄_fᵀ = (Σ_f g_f ξ_fᵀ) A: Σ g × w = (P₁₂ − P₂₁, P₂₀ − P₀₂, P₀₁ − P₁₀).
  const Eigen::Matrix3d p = detail::outer_sum(g, Eigen::Map<const Eigen::Matrix3Xd>(xi.data(), 3, g.cols())) * a;
  phi.tail<3>() << p(1, 2) - p(2, 1), p(2, 0) - p(0, 2), p(0, 1) - p(1, 0);
  return phi;
}

Eigen::MatrixXd reference_jacobian(const TisserandMatrix& g, const Eigen::Matrix3d& a, const VectorRef& xi) {
  check_tisserand_sizes(g, xi);
  const Eigen::Index n_f = g.cols();
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(9, 9 + 3 * n_f);
  for (int k = 0; k < kOrthogonalityRows; ++k) {
    const auto [i, j] = kPairs[static_cast<std::size_t>(k)];
    jac.block<1, 3>(k, 3 * i) += a.col(j).transpose();
    jac.block<1, 3>(k, 3 * j) += a.col(i).transpose();
  }
  for (Eigen::Index f = 0; f < n_f; ++f) {
    const Eigen::Matrix3d gx = skew(g.col(f));
    const Eigen::Vector3d x = xi.segment<3>(3 * f);
    // ∂(g × Aᵀx)/∂A(i, j) = g × (e_j x_i): column 3j + i.
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) jac.block<3, 1>(6, 3 * j + i) += gx.col(j) * x(i);
    jac.block<3, 3>(6, 9 + 3 * f) = gx * a.transpose();
  }
  return jac;
}

void reference_jacobian_transpose_product(const TisserandMatrix& g, const Eigen::Matrix3d& a, const VectorRef& xi,
                                          const Eigen::Matrix<double, 9, 1>& mu, Eigen::Ref<Eigen::VectorXd> out) {
  check_tisserand_sizes(g, xi);
  const Eigen::Index n_f = g.cols();
  if (out.size() != 9 + 3 * n_f)
    throw std::invalid_argument("reference_jacobian_transpose_product: the output has " + std::to_string(out.size()) +
                                " entries, not " + std::to_string(9 + 3 * n_f));
  Eigen::Matrix3d d_a = Eigen::Matrix3d::Zero();  // ∂/∂A, column j = ∂/∂a_j
  for (int k = 0; k < kOrthogonalityRows; ++k) {
    const auto [i, j] = kPairs[static_cast<std::size_t>(k)];
    d_a.col(i) += mu(k) * a.col(j);
    d_a.col(j) += mu(k) * a.col(i);
  }
  // The Tisserand rows, with c_f = μ_T × g_f (C = [μ_T]× G): ∂/∂A += Σ_f ξ_f c_fᵀ = −(Σ_f ξ_f g_fᵀ) [μ_T]×,
  // ∂/∂ξ_f = A c_f.
  const Eigen::Matrix3d mu_t = skew(mu.tail<3>());
  d_a.noalias() -= detail::outer_sum(Eigen::Map<const Eigen::Matrix3Xd>(xi.data(), 3, n_f), g) * mu_t;
  const Eigen::Matrix3d turn = a * mu_t;
  Eigen::Map<Eigen::Matrix3Xd>(out.data() + 9, 3, n_f).noalias() = turn * g;
  out.head<9>() = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(d_a.data());
}

Eigen::VectorXd reference_jacobian_transpose_product(const TisserandMatrix& g, const Eigen::Matrix3d& a,
                                                     const VectorRef& xi, const Eigen::Matrix<double, 9, 1>& mu) {
  Eigen::VectorXd out(9 + xi.size());
  reference_jacobian_transpose_product(g, a, xi, mu, out);
  return out;
}

Eigen::Matrix<double, 9, 1> reference_jacobian_product(const TisserandMatrix& g, const Eigen::Matrix3d& a,
                                                       const VectorRef& xi, const Eigen::Matrix3d& a_dot,
                                                       const VectorRef& xi_dot) {
  check_tisserand_sizes(g, xi);
  check_tisserand_sizes(g, xi_dot);
  Eigen::Matrix<double, 9, 1> rate;
  for (int k = 0; k < kOrthogonalityRows; ++k) {  // d/dt of Eq. 79
    const auto [i, j] = kPairs[static_cast<std::size_t>(k)];
    rate(k) = a_dot.col(i).dot(a.col(j)) + a.col(i).dot(a_dot.col(j));
  }
  // d/dt of Eq. 78, as in reference_residual: the axial vector of Ṗ.
  const auto fields = [&g](const VectorRef& x) { return Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, g.cols()); };
  const Eigen::Matrix3d p = detail::outer_sum(g, fields(xi_dot)) * a + detail::outer_sum(g, fields(xi)) * a_dot;
  rate.tail<3>() << p(1, 2) - p(2, 1), p(2, 0) - p(0, 2), p(0, 1) - p(1, 0);
  return rate;
}

Eigen::Matrix<double, 9, Eigen::Dynamic> reference_hessian_a_rows(const TisserandMatrix& g, const VectorRef& xi,
                                                                  const Eigen::Matrix<double, 9, 1>& lambda) {
  check_tisserand_sizes(g, xi);
  const Eigen::Index n_f = g.cols();
  Eigen::Matrix<double, 9, Eigen::Dynamic> rows = Eigen::Matrix<double, 9, Eigen::Dynamic>::Zero(9, 9 + 3 * n_f);
  for (int k = 0; k < kOrthogonalityRows; ++k) {  // λ_k a_i·a_j
    const auto [i, j] = kPairs[static_cast<std::size_t>(k)];
    rows.block<3, 3>(3 * i, 3 * j).diagonal().array() += lambda(k);
    rows.block<3, 3>(3 * j, 3 * i).diagonal().array() += lambda(k);
  }
  // λ · (g_f × Aᵀ x_f) = x_fᵀ A c_f with c_f = λ_T × g_f: the (A, x_f) cross derivative is
  // ∂²/∂A(i, l) ∂x_f(i) = c_f(l).
  const Eigen::Vector3d lambda_t = lambda.tail<3>();
  for (Eigen::Index f = 0; f < n_f; ++f) {
    const Eigen::Vector3d c = lambda_t.cross(g.col(f));
    for (int l = 0; l < 3; ++l)
      for (int i = 0; i < 3; ++i) rows(3 * l + i, 9 + 3 * f + i) += c(l);
  }
  return rows;
}

Eigen::MatrixXd reference_hessian(const TisserandMatrix& g, const Eigen::Matrix3d& a, const VectorRef& xi,
                                  const Eigen::Matrix<double, 9, 1>& lambda) {
  (void)a;  // the rows are bilinear in (A, ξ) and quadratic in A: the Hessian does not depend on the point
  const Eigen::Index n = 9 + 3 * g.cols();
  const Eigen::Matrix<double, 9, Eigen::Dynamic> rows = reference_hessian_a_rows(g, xi, lambda);
  Eigen::MatrixXd hessian = Eigen::MatrixXd::Zero(n, n);  // the ξξ block is zero
  hessian.topRows<9>() = rows;
  hessian.bottomLeftCorner(n - 9, 9) = rows.rightCols(n - 9).transpose();
  return hessian;
}

}  // namespace flexbody::runtime
