#include "flexbody/runtime/gcms_elastic.hpp"

#include "gcms_elastic_padded.hpp"

#include "../kernels/dense_product.hpp"
#include "../kernels/outer_sum.hpp"

#include <stdexcept>
#include <string>
#include <type_traits>

namespace flexbody::runtime {
namespace {

template <class Stiffness>
void check_stiffness_sizes(const Stiffness& k_hat, const VectorRef& xi) {
  if (k_hat.rows() != k_hat.cols() || k_hat.rows() % 3 != 0 || xi.size() != k_hat.rows())
    throw std::invalid_argument("GCMS elastic forces: K_hat is " + std::to_string(k_hat.rows()) + " x " +
                                std::to_string(k_hat.cols()) + " and xi has " + std::to_string(xi.size()) +
                                " entries; expected 3 n_f square and 3 n_f");
}

}  // namespace

Eigen::Matrix<double, Eigen::Dynamic, 9> body_frame_coordinates_derivative(const VectorRef& xi) {
  const Eigen::Index n_f = xi.size() / 3;
  Eigen::Matrix<double, Eigen::Dynamic, 9> d = Eigen::Matrix<double, Eigen::Dynamic, 9>::Zero(3 * n_f, 9);
  for (Eigen::Index f = 0; f < n_f; ++f)
    for (int j = 0; j < 3; ++j) d.block<1, 3>(3 * f + j, 3 * j) = xi.segment<3>(3 * f).transpose();
  return d;
}

Eigen::VectorXd body_frame_coordinates(const Eigen::Matrix3d& a, const VectorRef& xi) {
  Eigen::VectorXd xi_bar(xi.size());
  const Eigen::Index n_f = xi.size() / 3;  // as 3 x n_f matrices, one column per field: Ξ̄ = Aᵀ Ξ
  Eigen::Map<Eigen::Matrix3Xd>(xi_bar.data(), 3, n_f).noalias() = a.transpose() * Eigen::Map<const Eigen::Matrix3Xd>(xi.data(), 3, n_f);
  return xi_bar;
}

namespace {

// U and its gradient into `out`, with ξ̄ in `xi_bar`: sized once, no allocation when reused (the dense kinds of K̂).
template <class Stiffness>
void forces_into(const Stiffness& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi, ElasticForces& out,
                 Eigen::VectorXd& xi_bar) {
  check_stiffness_sizes(k_hat, xi);
  const Eigen::Index n_f = xi.size() / 3;
  xi_bar.resize(xi.size());  // as 3 x n_f matrices, one column per field: Ξ̄ = Aᵀ Ξ
  Eigen::Map<Eigen::Matrix3Xd>(xi_bar.data(), 3, n_f).noalias() = a.transpose() * Eigen::Map<const Eigen::Matrix3Xd>(xi.data(), 3, n_f);
  out.h.resize(xi.size());
  if constexpr (std::is_same_v<Stiffness, detail::PaddedMatrix>) {  // every iteration: the dispatched kernel
    k_hat.multiply(xi_bar.data(), out.h.data());
  } else if constexpr (std::is_same_v<Stiffness, Eigen::MatrixXd>) {
    detail::dense_product(k_hat, xi_bar.data(), out.h.data());
  } else {
    out.h = k_hat * xi_bar;
  }
  out.energy = 0.5 * xi_bar.dot(out.h);
  out.grad_xi.resize(xi.size());
  // With the 3-blocks as the columns of 3 x n_f matrices Ξ, H: ∂U/∂ξ = A H (Eq. 87), ∂U/∂A = Ξ Hᵀ (Eq. 86).
  const Eigen::Map<const Eigen::Matrix3Xd> h(out.h.data(), 3, n_f);
  Eigen::Map<Eigen::Matrix3Xd>(out.grad_xi.data(), 3, n_f).noalias() = a * h;
  Eigen::Map<Eigen::Matrix3d>(out.grad_a.data()) = detail::outer_sum(Eigen::Map<const Eigen::Matrix3Xd>(xi.data(), 3, n_f), h);
}

template <class Stiffness>
ElasticForces forces_of(const Stiffness& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi) {
  ElasticForces out;
  Eigen::VectorXd xi_bar;
  forces_into(k_hat, a, xi, out, xi_bar);
  return out;
}

template <class Stiffness>
ElasticTangent tangent_of(const Stiffness& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi, bool with_xi_xi) {
  check_stiffness_sizes(k_hat, xi);
  const Eigen::Index n = xi.size(), n_f = n / 3;
  const Eigen::Matrix<double, Eigen::Dynamic, 9> d = body_frame_coordinates_derivative(xi);
  const Eigen::VectorXd h = k_hat * body_frame_coordinates(a, xi);
  ElasticTangent t;
  // K̂ D once: U_aa = Dᵀ (K̂ D) and, K̂ being symmetric, Dᵀ K̂ Âᵀ = (Â (K̂ D))ᵀ.
  Eigen::Matrix<double, Eigen::Dynamic, 9> k_d = k_hat * d;
  t.aa = d.transpose() * k_d;
  for (Eigen::Index f = 0; f < n_f; ++f) k_d.middleRows<3>(3 * f) = a * k_d.middleRows<3>(3 * f);
  t.a_xi = k_d.transpose();
  for (Eigen::Index f = 0; f < n_f; ++f)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) t.a_xi(3 * j + i, 3 * f + i) += h(3 * f + j);
  if (!with_xi_xi) return t;
  // Â K̂ Âᵀ: column block g of K̂ times Aᵀ, then row block f times A.
  Eigen::MatrixXd k_at(n, n);
  for (Eigen::Index g = 0; g < n_f; ++g) k_at.middleCols<3>(3 * g) = k_hat.middleCols(3 * g, 3) * a.transpose();
  t.xi_xi.resize(n, n);
  for (Eigen::Index f = 0; f < n_f; ++f) t.xi_xi.middleRows<3>(3 * f) = a * k_at.middleRows<3>(3 * f);
  return t;
}

}  // namespace

ElasticForces elastic_forces(const Eigen::MatrixXd& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi) {
  return forces_of(k_hat, a, xi);
}

ElasticForces elastic_forces(const Eigen::SparseMatrix<double>& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi) {
  return forces_of(k_hat, a, xi);
}

ElasticForces detail::elastic_forces(const PaddedMatrix& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi) {
  return forces_of(k_hat, a, xi);
}

void detail::elastic_forces(const PaddedMatrix& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi, ElasticForces& out,
                            Eigen::VectorXd& xi_bar) {
  forces_into(k_hat, a, xi, out, xi_bar);
}

ElasticTangent elastic_tangent(const Eigen::MatrixXd& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi,
                               bool with_xi_xi) {
  return tangent_of(k_hat, a, xi, with_xi_xi);
}

ElasticTangent elastic_tangent(const Eigen::SparseMatrix<double>& k_hat, const Eigen::Matrix3d& a, const VectorRef& xi,
                               bool with_xi_xi) {
  return tangent_of(k_hat, a, xi, with_xi_xi);
}

}  // namespace flexbody::runtime
