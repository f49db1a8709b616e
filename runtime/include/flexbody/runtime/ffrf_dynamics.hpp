#pragma once
// flexbody/runtime/ffrf_dynamics.hpp: the equations of motion of one FFRF body (ffrf_model.hpp) and their exact
// derivatives, in the nodal-based form of Zwölfer & Gerstmayr (the paper's Eq. 12, with the invariants of
// ffrf_model.hpp in place of its nodal sums).
//
// With ω̄ = 2 Ḡ(p) ṗ and ω̄̇ = 2 Ḡ(p) p̈ (Ḡ = [−e, −[e]× + e0 I]; Ḡ(ṗ) ṗ = 0), ā = Aᵀ (τ̈ − g) (gravity enters as
// a frame acceleration) and ū = X̄ + Σ ψ_m η_m, the virtual work of the inertia forces ∫ρ δrᵀ r̈ is
// δτᵀ A F_τ + δθ̄ᵀ F_θ + δηᵀ F_η with δθ̄ = 2 Ḡ δp and, in the body frame,
//
//   F_τ = m ā + ω̄̇ × S + ω̄ × (ω̄ × S) + 2 ω̄ × (S_Ψ η̇) + S_Ψ η̈                     S = ∫ρ ū
//   F_θ = S × ā + I_θθ ω̄̇ + ω̄ × (I_θθ ω̄) + 2 (ω̄ Σ η̇_m tr P_m − Σ η̇_m P_m ω̄) + I_θf η̈
//   F_η,m = S_mᵀ ā + I_θf,mᵀ ω̄̇ + ω̄ᵀ P_m ω̄ − |ω̄|² tr P_m + 2 ω̄ · Σ_n η̇_n ∫ρ ψ_n × ψ_m + (M_ff η̈)_m
//
// with P_m = ∫ρ ψ_m ūᵀ, I_θθ = ∫ρ [ū]×ᵀ[ū]× (the deformed body's inertia tensor about the frame origin) and
// I_θf,m = ∫ρ ū × ψ_m. The body's residual is R = [A F_τ; 2 Ḡᵀ F_θ; F_η + K_ff η + D_ff η̇], and its equations are
// R + Φ_qᵀ λ = Q (applied forces), with the normalisation pᵀp = 1 among the constraints. Every term is O(n_m²).

#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/vector_ref.hpp"

#include <Eigen/Core>

namespace flexbody::runtime {

/// A(p) = (e0² − eᵀe) I + 2 e eᵀ + 2 e0 [e]×: homogeneous of degree 2, a rotation for pᵀp = 1.
[[nodiscard]] Eigen::Matrix3d euler_rotation(const Eigen::Vector4d& p);
/// The unit Euler parameters of a rotation matrix (e0 ≥ 0).
[[nodiscard]] Eigen::Vector4d euler_parameters(const Eigen::Matrix3d& a);
/// ∂(A(p) x)/∂p (3 x 4) for a fixed x.
[[nodiscard]] Eigen::Matrix<double, 3, 4> euler_rotation_derivative(const Eigen::Vector4d& p, const Eigen::Vector3d& x);
/// Ḡ(p) = [−e, −[e]× + e0 I] (3 x 4): ω̄ = 2 Ḡ(p) ṗ is the body-frame angular velocity.
[[nodiscard]] Eigen::Matrix<double, 3, 4> euler_body_velocity_matrix(const Eigen::Vector4d& p);

/// Scratch of one evaluation: the η-dependent invariants S, P_m, I_θθ, I_θf and buffers, sized for the model's modes
/// at first use, so that evaluations with the same workspace allocate nothing (a System keeps one per body).
struct FfrfWorkspace {
  Eigen::Vector3d s;          ///< S = ∫ρ ū
  Eigen::Matrix3d i_tt;       ///< I_θθ
  Eigen::Matrix3Xd p;         ///< 3 x 3 n: P_m = ∫ρ ψ_m ūᵀ
  Eigen::Matrix3Xd i_tf;      ///< 3 x n: ∫ρ ū × ψ_m
  Eigen::MatrixXd stacked;    ///< 3 n x 3: Σ_k η_k J2_mk
  Eigen::Matrix3Xd gyro;      ///< 3 x n: Σ_k η̇_k ∫ρ ψ_k × ψ_m
  Eigen::VectorXd body;       ///< F̄ (6 + n)
  void resize(Eigen::Index modes);
};

/// The residual of one FFRF body (7 + n_m) at coordinates q_b, velocities v_b and accelerations a_b under gravity g
/// [m/s²]: inertia forces, gravity and the elastic and damping forces (see above). One pass over the invariants.
[[nodiscard]] Eigen::VectorXd ffrf_residual(const FfrfModel& model, const VectorRef& q_b, const VectorRef& v_b,
                                            const VectorRef& a_b, const Eigen::Vector3d& gravity);
/// The same into `out` (7 + n_m), with no allocation once `work` has been used for this model.
void ffrf_residual(const FfrfModel& model, const VectorRef& q_b, const VectorRef& v_b, const VectorRef& a_b,
                   const Eigen::Vector3d& gravity, FfrfWorkspace& work, Eigen::Ref<Eigen::VectorXd> out);

/// M(q) x: the part of the residual linear in the accelerations.
[[nodiscard]] Eigen::VectorXd ffrf_mass_product(const FfrfModel& model, const VectorRef& q_b, const VectorRef& x);
void ffrf_mass_product(const FfrfModel& model, const VectorRef& q_b, const VectorRef& x, FfrfWorkspace& work,
                       Eigen::Ref<Eigen::VectorXd> out);

/// −R at zero acceleration: gravity, the quadratic velocity vector and the elastic and damping forces (what
/// System::forces holds for the body).
[[nodiscard]] Eigen::VectorXd ffrf_forces(const FfrfModel& model, const VectorRef& q_b, const VectorRef& v_b,
                                          const Eigen::Vector3d& gravity);

/// The exact derivatives of the residual: mass = ∂R/∂a = M(q) (symmetric, singular along p: Ḡ(p) p = 0, which the
/// normalisation row makes up for), stiffness = ∂R/∂q and damping = ∂R/∂v, all (7 + n_m) square.
struct FfrfTangent {
  Eigen::MatrixXd mass, stiffness, damping;
};
[[nodiscard]] FfrfTangent ffrf_tangent(const FfrfModel& model, const VectorRef& q_b, const VectorRef& v_b,
                                       const VectorRef& a_b, const Eigen::Vector3d& gravity);

/// T = ½ q̇ᵀ M(q) q̇ [J], and the elastic energy ½ ηᵀ K_ff η [J].
[[nodiscard]] double ffrf_kinetic_energy(const FfrfModel& model, const VectorRef& q_b, const VectorRef& v_b);
[[nodiscard]] double ffrf_elastic_energy(const FfrfModel& model, const VectorRef& q_b);
/// S(η) = ∫ρ ū [kg m], body frame: the centre of mass of the deformed body is τ + A S / m.
[[nodiscard]] Eigen::Vector3d ffrf_first_moment(const FfrfModel& model, const VectorRef& q_b);

/// The body-frame field coordinates ξ̄ = Σ_m η_m c_m (3 n_f) of a floating-frame body: what stresses are recovered
/// from (the rigid part of an interface frame's modes has no strain).
[[nodiscard]] Eigen::VectorXd ffrf_field_coordinates(const FfrfModel& model, const VectorRef& q_b);

/// Improved-GCMS coordinates [τ_g; a_g; ξ] (12 + 3 n_f) that put every node where the body's coordinates do,
/// r_i = τ_g + A_g X̄_i + Σ_f Ῡ'_if ξ_f: τ_g = τ + A Σ η_m W_m(0, :)ᵀ, A_g = A (I + Σ η_m W_m(1:4, :)ᵀ) and
/// ξ_f = A ξ̄_f. For a GCMS body, q_b itself. Outputs written for GCMS coordinates (pictures, momenta) read these. In
/// the mean-axis frame A_g = A; in an interface frame A_g carries the frame's small rotation off the mean axes.
[[nodiscard]] Eigen::VectorXd gcms_coordinates(const BodyModel& model, const VectorRef& q_b);
/// Their rates, d/dt of gcms_coordinates along (q_b, v_b).
[[nodiscard]] Eigen::VectorXd gcms_velocities(const BodyModel& model, const VectorRef& q_b, const VectorRef& v_b);

}  // namespace flexbody::runtime
