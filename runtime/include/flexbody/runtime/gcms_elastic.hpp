#pragma once
// flexbody/runtime/gcms_elastic.hpp: the elastic energy of an improved-GCMS body and its derivatives
// (Zwölfer & Gerstmayr 2023, Eqs. 86-87 and 96; formulations.md, "The Method": elastic forces).
//
//   U = ½ ξ̄ᵀ K̂ ξ̄,   ξ̄_f = Aᵀ ξ_f (the fields' coordinates in the body frame),   h = K̂ ξ̄
//   ∂U/∂ξ_f = A h_f,  ∂U/∂A = Σ_f ξ_f h_fᵀ  (a = vec(A), column-major: a[3j + i] = A(i, j))
//
// With D = ∂ξ̄/∂a (block f = I3 ⊗ ξ_fᵀ, 3 x 9) the Hessian is
//   U_aa = Dᵀ K̂ D,   U_aξ = Dᵀ K̂ Âᵀ + [h_0 ⊗ I3 … h_{n_f−1} ⊗ I3],   U_ξξ = Â K̂ Âᵀ  (Â = I ⊗ A).
// Every call costs O((3 n_f)²): no n_n-sized work at run time.

#include "flexbody/runtime/vector_ref.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace flexbody::runtime {

using Vector9d = Eigen::Matrix<double, 9, 1>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Matrix9Xd = Eigen::Matrix<double, 9, Eigen::Dynamic>;

struct ElasticForces {
  double energy = 0.0;      ///< U [J]
  Vector9d grad_a;          ///< ∂U/∂a
  Eigen::VectorXd grad_xi;  ///< ∂U/∂ξ (3 n_f)
  Eigen::VectorXd h;        ///< K̂ ξ̄: the fields' elastic forces in the body frame (3 n_f)
};

struct ElasticTangent {
  Matrix9d aa;            ///< ∂²U/∂a²
  Matrix9Xd a_xi;         ///< ∂²U/∂a∂ξ (9 x 3 n_f)
  Eigen::MatrixXd xi_xi;  ///< ∂²U/∂ξ² = Â K̂ Âᵀ (3 n_f square)
};

/// ξ̄ = Âᵀ ξ.
[[nodiscard]] Eigen::VectorXd body_frame_coordinates(const Eigen::Matrix3d& a, const VectorRef& xi);

/// D = ∂ξ̄/∂a (3 n_f x 9): row 3f + j, column 3j + i holds ξ_f[i] (ξ̄ is linear in a for fixed ξ).
[[nodiscard]] Eigen::Matrix<double, Eigen::Dynamic, 9> body_frame_coordinates_derivative(const VectorRef& xi);

/// U and its gradient for K̂ (3 n_f square, symmetric; dense, or sparse for the full-order body), A and ξ (3 n_f).
[[nodiscard]] ElasticForces elastic_forces(const Eigen::MatrixXd& k_hat, const Eigen::Matrix3d& a,
                                           const VectorRef& xi);
[[nodiscard]] ElasticForces elastic_forces(const Eigen::SparseMatrix<double>& k_hat, const Eigen::Matrix3d& a,
                                           const VectorRef& xi);

/// The Hessian of U (the elastic tangent stiffness). Without `with_xi_xi` the ξξ block (Â K̂ Âᵀ, which the
/// constant-core Newton solve never forms) is left empty.
[[nodiscard]] ElasticTangent elastic_tangent(const Eigen::MatrixXd& k_hat, const Eigen::Matrix3d& a,
                                             const VectorRef& xi, bool with_xi_xi = true);
[[nodiscard]] ElasticTangent elastic_tangent(const Eigen::SparseMatrix<double>& k_hat, const Eigen::Matrix3d& a,
                                             const VectorRef& xi, bool with_xi_xi = true);

}  // namespace flexbody::runtime
