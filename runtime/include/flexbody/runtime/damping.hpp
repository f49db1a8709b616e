#pragma once
// flexbody/runtime/damping.hpp: structural damping of a body's deformation, as a matrix D̂ (3 n_f square) acting on
// the body-frame field velocities: the dissipation is R = ½ ξ̄̇ᵀ D̂ ξ̄̇ with ξ̄̇_f = d/dt (Aᵀ ξ_f) = Ȧᵀ ξ_f + Aᵀ ξ̇_f, so
// rigid motion is never damped. The generalized forces are −∂R/∂ξ̇ = −Â D̂ ξ̄̇ and −∂R/∂ȧ = −Dᵀ D̂ ξ̄̇ (D = ∂ξ̄/∂a).

#include "flexbody/runtime/body_model.hpp"

#include <Eigen/Core>

namespace flexbody::runtime {

/// Modal damping (Abaqus *MODAL DAMPING, Adams' CRATIO): mode m of the k kept is damped with ratio ζ_m,
/// D̂ = Σ_m 2 ζ_m ω_m c_m c_mᵀ with c_m the mode's coordinates in the fields (c_m[3f + d] = C(f, 3m + d),
/// orthonormal because the fields and modes are M-orthonormal; K̂ c_m = ω_m² c_m). The other directions of the
/// generalized basis stay undamped. Throws std::invalid_argument for a wrong count or ζ outside [0, 1].
[[nodiscard]] Eigen::MatrixXd modal_damping(const BodyModel& model, const Eigen::VectorXd& ratios);

/// Rayleigh damping of the deformation, D̂ = α (G_ff ⊗ I3) + β K̂ [α in 1/s, β in s]: mode m then has the ratio
/// α / (2 ω_m) + β ω_m / 2. Throws std::invalid_argument for negative or non-finite α, β.
[[nodiscard]] Eigen::MatrixXd rayleigh_damping(const BodyModel& model, double alpha, double beta);

}  // namespace flexbody::runtime
