#pragma once
// flexbody/runtime/reference_constraints.hpp: the reference conditions of an improved-GCMS body (Eq. 88).
//
// Rows 0-5, orthogonality (Eq. 79): a_iᵀ a_j − δ_ij for (i, j) = (0,0), (1,1), (2,2), (0,1), (0,2), (1,2), a_i the
// columns of A. Rows 6-8, rotational Tisserand (Eq. 78): Σ_f g_f × ξ̄_f with ξ̄_f = Aᵀ ξ_f and g_f = G[1:4, 4 + f]
// (BodyModel::tisserand). The translational Tisserand rows (Eq. 77) vanish identically because every field is
// M-orthogonal to translations (G[0, 4:] = 0, checked by the reader), so they are not imposed. A rigid body
// (n_f = 0) has the orthogonality rows only in effect: its Tisserand rows are identically zero and are dropped
// by the caller.
//
// Derivatives are with respect to [a; ξ] (9 + 3 n_f), exact: the rows are quadratic (orthogonality) and bilinear
// (Tisserand), so the λ-weighted Hessian is constant in q for fixed λ.

#include "flexbody/runtime/vector_ref.hpp"

#include <Eigen/Core>

namespace flexbody::runtime {

inline constexpr int kOrthogonalityRows = 6;
inline constexpr int kTisserandRows = 3;

using TisserandMatrix = Eigen::Matrix<double, 3, Eigen::Dynamic>;

/// The 9 residuals (6 orthogonality, 3 Tisserand).
[[nodiscard]] Eigen::Matrix<double, 9, 1> reference_residual(const TisserandMatrix& g, const Eigen::Matrix3d& a,
                                                             const VectorRef& xi);

/// ∂Φ/∂[a; ξ] (9 x (9 + 3 n_f)).
[[nodiscard]] Eigen::MatrixXd reference_jacobian(const TisserandMatrix& g, const Eigen::Matrix3d& a,
                                                 const VectorRef& xi);

/// Jᵀ μ for the 9 rows (Jacobian over [a; ξ], 9 + 3 n_f) without forming J: O(n_f). With c_f = μ_T × g_f,
/// the Tisserand rows give ∂/∂A = Σ_f ξ_f c_fᵀ and ∂/∂ξ_f = A c_f; the orthogonality rows μ_k (a_i·a_j − δ_ij)
/// give μ_k a_j on a_i and μ_k a_i on a_j.
[[nodiscard]] Eigen::VectorXd reference_jacobian_transpose_product(const TisserandMatrix& g, const Eigen::Matrix3d& a,
                                                                   const VectorRef& xi,
                                                                   const Eigen::Matrix<double, 9, 1>& mu);
/// The same into `out` (9 + 3 n_f), without allocating.
void reference_jacobian_transpose_product(const TisserandMatrix& g, const Eigen::Matrix3d& a, const VectorRef& xi,
                                          const Eigen::Matrix<double, 9, 1>& mu, Eigen::Ref<Eigen::VectorXd> out);

/// J [ȧ; ξ̇] for the 9 rows without forming J: O(n_f), the velocity constraints of the stabilised index-2 form.
/// Orthogonality: ȧ_i·a_j + a_i·ȧ_j; Tisserand: the axial vector of Ṗ = (Σ_f g_f ξ̇_fᵀ) A + (Σ_f g_f ξ_fᵀ) Ȧ.
[[nodiscard]] Eigen::Matrix<double, 9, 1> reference_jacobian_product(const TisserandMatrix& g, const Eigen::Matrix3d& a,
                                                                     const VectorRef& xi, const Eigen::Matrix3d& a_dot,
                                                                     const VectorRef& xi_dot);

/// The first 9 rows (those of a) of Σ_k λ_k ∂²Φ_k/∂[a; ξ]² (9 x (9 + 3 n_f)): all of it that is not zero, since
/// the ξξ block vanishes (Φ is linear in ξ for fixed A). O(n_f), for large bodies.
[[nodiscard]] Eigen::Matrix<double, 9, Eigen::Dynamic> reference_hessian_a_rows(const TisserandMatrix& g,
                                                                               const VectorRef& xi,
                                                                               const Eigen::Matrix<double, 9, 1>& lambda);

/// Σ_k λ_k ∂²Φ_k/∂[a; ξ]² ((9 + 3 n_f) square, symmetric).
[[nodiscard]] Eigen::MatrixXd reference_hessian(const TisserandMatrix& g, const Eigen::Matrix3d& a,
                                                const VectorRef& xi, const Eigen::Matrix<double, 9, 1>& lambda);

}  // namespace flexbody::runtime
