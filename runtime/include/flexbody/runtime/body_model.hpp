#pragma once
// flexbody/runtime/body_model.hpp: the constant data of one improved-GCMS body (Zwölfer & Gerstmayr 2023,
// Eqs. 85-89; FORMULATION.md sections 2-4), loaded from a body file and truncated to what a scene needs.
//
// Coordinates q = [τ (3); a = vec(A) (9, column-major, Eq. 27); ξ (3 n_f)], positions r = (Y ⊗ I3) q with
// Y = [1, X̄, Ῡ'] (Eq. 61), mass matrix G ⊗ I3 (Eq. 66, constant), elastic energy ½ ξ̄ᵀ K̂ ξ̄ with ξ̄_f = Aᵀ ξ_f
// (Eqs. 87, 96). A rigid body is the same with n_f = 0: one code path.

#include "flexbody/format/body_data.hpp"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace flexbody::runtime {

/// One body's constant blocks. The GCMS fields are an M_s-orthonormal basis of the modes' fields built in mode
/// order (SCHEMA.md), so the first k modes are exactly the fields with field_mode < k and the leading blocks
/// of G, K̂, the markers and the stress modes: truncation is slicing.
struct BodyModel {
  std::string source;               ///< the body file (for messages)
  Eigen::Index modes = 0;           ///< modes kept (0: rigid)
  double mass = 0.0;                ///< [kg]
  Eigen::MatrixXd mass_matrix;      ///< G ((4 + n_f) square)
  Eigen::MatrixXd stiffness;        ///< K̂ (3 n_f square) [s^-2]
  /// g_f = G[1:4, 4 + f] (3 x n_f) [kg^1/2 m]: the rotational Tisserand constraint is Σ_f g_f × ξ̄_f = 0 (Eq. 78).
  Eigen::Matrix<double, 3, Eigen::Dynamic> tisserand;
  std::vector<format::Interface> interfaces;      ///< y_row and rotation truncated to n_f
  std::vector<format::RecoveryRegion> recovery;   ///< stress modes truncated to 3 n_f columns
  Eigen::MatrixXd fields;                         ///< Ῡ' (n_n x n_f), for nodal displacements
  /// C (n_f x 3 k): mode m's displacement is Σ_f,d C(f, 3m + d) Ῡ'_f e_d, so its modal coordinate in a state is
  /// η_m = Σ_f,d C(f, 3m + d) ξ̄_f[d] (the modes are M-orthonormal), and a pure mode m has ξ̄_f = η C(f, 3m..3m+2).
  Eigen::MatrixXd mode_coefficients;
  Eigen::VectorXd frequencies_hz;                 ///< of the k modes kept
  /// D̂ (3 n_f square) [1/s] on the body-frame field velocities (damping.hpp); empty: undamped.
  Eigen::MatrixXd damping;
  format::RowMatrixX3d nodes;                     ///< X̄ (body frame) [m]
  format::RowMatrixX3i surface_triangles;         ///< the mesh's boundary, for pictures (paraview_series.hpp)

  /// G[0, 4:] (n_f): zero when every field is M-orthogonal to translations (every body file); otherwise (the
  /// full-order reference, full_order.hpp) the translational Tisserand rows Σ_f G[0, 4 + f] ξ_f = 0 (Eq. 77) are
  /// imposed too.
  [[nodiscard]] bool needs_translational_tisserand() const {
    return field_count() > 0 && mass_matrix.row(0).tail(field_count()).cwiseAbs().maxCoeff() > 1e-12 * mass;
  }
  [[nodiscard]] Eigen::Index field_count() const { return stiffness.rows() / 3; }
  [[nodiscard]] Eigen::Index coordinate_count() const { return 12 + stiffness.rows(); }
  [[nodiscard]] bool rigid() const { return field_count() == 0; }
};

/// The body of `file` with its first `modes` modes (nullopt: all; 0: rigid, from the mass properties in G).
/// Throws std::invalid_argument naming the file if `modes` is negative or exceeds the modes it holds.
[[nodiscard]] BodyModel make_body_model(const format::BodyData& body, std::optional<Eigen::Index> modes,
                                        const std::string& source = "body");

/// How many GCMS fields the first k modes have (the fields with field_mode < k).
[[nodiscard]] Eigen::Index fields_of_first_modes(const format::Gcms& gcms, Eigen::Index k);

}  // namespace flexbody::runtime
