#pragma once
// flexbody/preprocess/static_correction.hpp: static correction (attachment) modes for load points.
//
// A load point is a patch of surface nodes where a force or a torque acts in the simulation. Normal modes
// alone converge slowly to the static deflection under such a local load. The standard remedy adds, per
// unit load f, its residual static response (residual flexibility; for a free body, attachment modes with
// inertia relief, Craig & Chang 1977):
//
//   K̄ u = (I − M̄ W Wᵀ) f,   Wᵀ M̄ u = 0,   W = [rigid-body fields, normal modes already in the basis],
//
// i.e. the part of K̄⁺ f the normal modes do not hold. The responses are M̄-orthonormalised and K̄ is
// diagonalised on them (Rayleigh-Ritz), so they join the basis as "modes" with Ritz frequencies above the
// last normal mode's, and the normal modes stay exact eigenvectors.

#include "flexbody/format/body_data.hpp"
#include "flexbody/preprocess/interfaces.hpp"
#include "flexbody/preprocess/shift_invert_operator.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace flexbody::preprocess {

/// The six unit loads of a load point: forces along x, y, z [N], moments about x, y, z [N m] (the names of the
/// body file's interface load cases, format::kInterfaceLoadCases).
inline constexpr const std::array<const char*, 6>& kUnitLoadNames = format::kInterfaceLoadCases;

/// A load point as the body spec asks for it (input frame, lengths in the input's unit like interfaces).
/// It is also an rbe3 interface of the same name, so the runtime can apply its loads there.
struct LoadPointRequest {
  std::string name;
  Selector select;
  std::array<bool, 6> loads = {true, true, true, true, true, true};  ///< which of kUnitLoadNames
};

/// A selected load point: a surface patch (nodes, area weights summing to 1) and its reference point
/// (the weighted centroid, same frame as the nodes).
struct LoadPoint {
  std::string name;
  Eigen::VectorXi nodes;
  Eigen::VectorXd weights;
  Eigen::Vector3d reference_point = Eigen::Vector3d::Zero();
  std::array<bool, 6> loads = {true, true, true, true, true, true};
};

/// The nodal force vectors (3 n_n x s, node-interleaved) of every selected unit load, distributed over
/// the patch as an rbe3 element does: a force e_k gives node i the force w_i e_k; a moment e_k about the
/// reference point c gives f_i = w_i (J⁻¹ e_k) × d_i with d_i = X_i − c and J = Σ w_i (|d_i|² I − d_i d_iᵀ),
/// so Σ f_i = 0 and Σ d_i × f_i = e_k. Throws std::invalid_argument naming the load point if it asks for
/// no load, or for moments on nodes that lie on a line (J singular).
[[nodiscard]] Eigen::MatrixXd unit_load_vectors(const RowMatrixX3d& nodes, const std::vector<LoadPoint>& points);

/// "name:fx", ... for the columns of unit_load_vectors.
[[nodiscard]] std::vector<std::string> unit_load_labels(const std::vector<LoadPoint>& points);

/// How the static correction went, for the report.
struct StaticCorrectionStats {
  Eigen::Index loads = 0;  ///< unit loads asked for
  /// Loads whose residual response adds no new direction (it lies, to 1e-6 of its norm, in the span of
  /// the known fields and of the other responses), and so no mode.
  Eigen::Index dropped = 0;
  int iterations = 0;  ///< conjugate-gradient iterations over all loads (one factor solve each)
  double max_relative_residual = 0.0;  ///< max ‖b − K̄u‖₂ / ‖b‖₂ of the static solves (b the projected load)
  /// max over the solves of that residual over its rounding floor ε ‖|K̄||u|‖₂ / ‖b‖₂ (eigen_residual.hpp); each
  /// residual is at most max(1e-8, kResidualFloorFactor x its floor).
  double max_residual_to_floor = 0.0;
};

/// Patches a part holds rigid (its rbe2 interfaces), for relieved_static_responses.
struct RigidPatches {
  const RowMatrixX3d* nodes = nullptr;  ///< the mesh's node coordinates, which the patches' nodes index
  std::vector<RigidInterface> patches;  ///< disjoint; reference points in the same frame as `nodes`
};

struct StaticCorrectionModes {
  /// n x (loads − dropped), M̄-orthonormal, M̄-orthogonal to `known`, K̄-orthogonal; ascending in their
  /// Ritz values.
  Eigen::MatrixXd vectors;
  Eigen::VectorXd eigenvalues;  ///< Ritz values ψᵀ K̄ ψ [rad²/s²]
  StaticCorrectionStats stats;
};

/// The static responses u of the loads (columns of `loads`, 3 n_n x s) on the M̄-complement of `known` (n x w,
/// M̄-orthonormal, holding every zero-energy field of K̄): K̄ u = (I − M̄ W Wᵀ) f, Wᵀ M̄ u = 0. With W the six
/// rigid-body fields this is the free body's response with inertia relief: the load is balanced by the rigid-body
/// accelerations it causes. By conjugate gradients preconditioned by `solve` (a factorization of K̄ − σM̄, σ <= 0).
/// A load wholly in the known fields gives a zero column. `stats` counts the loads, the iterations and the worst
/// residual (added to what it holds). Errors begin with `what` and name the load by `names` (one per column) or
/// by its number. Throws std::runtime_error if a solve does not converge (its true residual above max(1e-8,
/// kResidualFloorFactor x its rounding floor)), std::invalid_argument for sizes that differ.
///
/// `rigid` lists patches (rbe2 interfaces of `rigid.nodes`; disjoint, a node in two is refused) that the part holds
/// rigid: the responses are then sought in V, the displacements that move each patch rigidly and hold no rigid-body
/// field, by the same conjugate gradients with forces and displacements both mapped by Q, the Euclidean projector onto
/// V (Galerkin: Q K̄ u = Q f). A load on such a patch acts through its resultant and moment; the patch's own constraint
/// forces (a hub holding a bore) are what Q removes. Throws std::invalid_argument for a patch on a line.
[[nodiscard]] Eigen::MatrixXd relieved_static_responses(ShiftSolve& solve, const SparseMatrix& stiffness_upper,
                                                        const SparseMatrix& scalar_mass_upper,
                                                        const Eigen::MatrixXd& known, const Eigen::MatrixXd& loads,
                                                        StaticCorrectionStats& stats,
                                                        const std::vector<std::string>& names = {},
                                                        std::string_view what = "static solve",
                                                        const RigidPatches& rigid = {});

/// Residual static correction modes (see the top of this file). `solve` is a factorization of K̄ − σM̄
/// with σ <= 0 (its shift as set; for σ < 0 it should deflate the rigid-body fields); `known` (n x w) must be
/// M̄-orthonormal and hold every zero-energy field of K̄ (the six rigid-body fields of a free body) and the
/// normal modes. Each load is solved by conjugate gradients on the M̄-complement of `known`, preconditioned
/// by the factorization: the preconditioned spectrum is λ / (λ − σ) with λ >= the first eigenvalue not in
/// `known`, so a handful of solves reach 1e-10. Throws std::runtime_error if a solve does not converge (its true
/// residual above max(1e-8, kResidualFloorFactor x its rounding floor)).
[[nodiscard]] StaticCorrectionModes static_correction_modes(ShiftSolve& solve, const SparseMatrix& stiffness_upper,
                                                            const SparseMatrix& scalar_mass_upper,
                                                            const Eigen::MatrixXd& known, const Eigen::MatrixXd& loads);

}  // namespace flexbody::preprocess
