#pragma once
// flexbody/runtime/ffrf_model.hpp: the floating frame of reference formulation (FFRF) with modal reduction, built
// from the same body file and modes as the improved GCMS. Coordinates q = [τ (3); p (4, Euler parameters); η (n_m)],
// nodal positions r = τ + A(p) (X̄ + Σ_m ψ_m η_m). The inertia invariants are the consistent-mass integrals of
// Zwölfer & Gerstmayr (Acta Mech. 232, 2021), with no lumped-mass approximation: every one of them is a bilinear
// form of nodal fields with M_s, and every mode is a combination of the columns of Y = [1, X̄, Ῡ'], so each is a
// product with G = Yᵀ M_s Y (formulations.md, "The Method": nodal fields) and needs no n_n-sized work:
//
//   mode m's displacement u_m = (Y ⊗ I3)-combination with coefficients W_m ((4 + n_f) x 3: u_m(i) = W_mᵀ Y(i, :)ᵀ)
//   ∫ρ X̄ = G[1:4, 0],  ∫ρ X̄ X̄ᵀ = G[1:4, 1:4],  ∫ρ ψ_m = W_mᵀ G[:, 0],  ∫ρ X̄ ψ_mᵀ = G[1:4, :] W_m,
//   ∫ρ ψ_m ψ_nᵀ = W_mᵀ G W_n,  modal stiffness c_mᵀ K̂ c_n (c_m: W_m's field rows; rigid motion has no strain).
//
// Why Euler parameters: A(p) is quadratic in p, so every derivative the Newton matrix needs is a short polynomial,
// the parametrisation has no singular orientation (a fast spin passes through every angle), and the one
// normalisation row pᵀp = 1 is a constraint like the others, which the integrator already carries (a rotation vector
// would need a reparametrisation switch inside the time step, which generalized-α on q does not have).
//
// The frame in which linear elasticity is measured:
//  - mean_axis: the body file's modes as they are. They are M-orthogonal to the rigid modes, so ∫ρ ψ_m = 0 and
//    ∫ρ X̄ × ψ_m = 0: the linearised Tisserand (mean-axis) frame, the frame of the improved GCMS.
//  - interface: the frame rigidly attached to an interface (the root frame of Craig-Bampton practice and of
//    Exudyn): each mode less the rigid motion that brings the interface back, ψ_m − t_m − θ_m × (X̄ − X̄_c), with
//    t_m and θ_m the interface's displacement and rotation in the mode. Same strains, same stiffness; the inertia
//    invariants then couple (∫ρ ψ_m ≠ 0, a modal mass that is not I).

#include "flexbody/runtime/body_model.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace flexbody::runtime {

enum class FloatingFrame { mean_axis, interface };

struct FfrfModel {
  FloatingFrame frame = FloatingFrame::mean_axis;
  std::string interface_name;  ///< FloatingFrame::interface: the interface the frame is attached to
  Eigen::Index modes = 0;      ///< n_m
  double mass = 0.0;           ///< m [kg]
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();          ///< ∫ρ X̄ [kg m] (zero: origin at the centre of mass)
  Eigen::Matrix3d second_moment = Eigen::Matrix3d::Zero();         ///< J0 = ∫ρ X̄ X̄ᵀ [kg m²]
  Eigen::Matrix3Xd mode_first_moments;   ///< S_Ψ (3 x n_m): column m = ∫ρ ψ_m [kg^1/2]
  Eigen::Matrix3Xd mode_second_moments;  ///< J1 (3 x 3 n_m): block m = ∫ρ X̄ ψ_mᵀ [kg^1/2 m]
  Eigen::MatrixXd mode_products;         ///< J2 (3 n_m square): block (m, n) = ∫ρ ψ_m ψ_nᵀ [1]
  /// (3 n_m x n_m): rows 3k..3k+2 of column m = ∫ρ ψ_k × ψ_m = axial(J2_km) [1], for the gyroscopic terms
  Eigen::MatrixXd mode_cross;
  Eigen::MatrixXd modal_mass;            ///< M_ff (n_m square): tr of J2's blocks (I in the mean-axis frame)
  Eigen::MatrixXd modal_stiffness;       ///< K_ff (n_m square) [1/s²]: diag(ω²) for M-orthonormal modes
  Eigen::MatrixXd modal_damping;         ///< D_ff (n_m square) [1/s], empty: undamped
  /// W ((4 + n_f) x 3 n_m): columns 3m..3m+2 are mode m's displacement as coefficients of Y's columns. Rows 4.. are
  /// the body-frame field coordinates ξ̄ of the mode; rows 0..3 its rigid part (zero in the mean-axis frame).
  Eigen::MatrixXd shapes;
  /// The small rotation each mode's rigid part adds to every marker (3 x n_m): zero in the mean-axis frame, −θ_m in
  /// the interface frame.
  Eigen::Matrix3Xd rigid_rotations;
  /// The geometric stiffness of the body model's prestress cases on the modes (n_m square each, one per case of
  /// BodyModel::prestress) [1/s² per unit λ]: Σ_d W_dᵀ Ĝ_k W_d over the directions d, W_d the columns 3m + d (the
  /// displacement measured from this frame, rigid part included); empty without prestress cases.
  std::vector<Eigen::MatrixXd> prestress;
};

/// The FFRF of a (GCMS) body model with its modes, in the given frame (`interface`: the name of one of the body
/// file's interfaces, for FloatingFrame::interface). Throws std::invalid_argument naming the body for an unknown
/// interface or a full-order model. A model without modes gives a rigid body in Euler parameters.
[[nodiscard]] FfrfModel make_ffrf_model(const BodyModel& model, FloatingFrame frame, const std::string& interface = {});

}  // namespace flexbody::runtime
