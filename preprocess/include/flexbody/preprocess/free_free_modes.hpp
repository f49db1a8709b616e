#pragma once
// flexbody/preprocess/free_free_modes.hpp: elastic free-free eigenmodes of an unconstrained body.

#include "flexbody/preprocess/eigensolver.hpp"
#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/static_correction.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <Eigen/Core>

#include <functional>
#include <string>

namespace flexbody::preprocess {

struct FreeFreeOptions {
  /// Number of elastic modes wanted (rigid-body modes never count); 0 = not set.
  int modes = 0;
  /// All elastic modes up to this frequency [Hz]; 0 = not set. With `modes` too, `modes` caps the count.
  double fmax_hz = 0.0;
  EigensolverOptions solver;
  /// Shift sigma [rad^2/s^2] (must be < 0); 0 = automatic: -(2 pi f_s)^2 with f_s one twentieth of the
  /// first axial frequency of a bar as long as the body's bounding-box diagonal, sqrt(E/rho)/(2L).
  /// That lies below the first elastic frequency of compact bodies. For slender ones |sigma| may exceed
  /// the first eigenvalues: still accurate (the rigid-body modes are deflated), but Lanczos then needs
  /// more iterations.
  double shift = 0.0;
  /// Called with a short message before each solver run (for progress on a terminal).
  std::function<void(const std::string&)> progress;
};

struct FreeFreeModes {
  /// omega^2 [rad^2/s^2], ascending, elastic only: the normal modes, then the static correction modes'
  /// Ritz values (all above the normal modes').
  Eigen::VectorXd eigenvalues;
  Eigen::VectorXd frequencies_hz;
  /// ||K phi - omega^2 M phi||_2 / ||K phi||_2 and its rounding floor (eigen_residual.hpp). Each normal mode's
  /// residual is at most max(1e-8, kResidualFloorFactor x its floor); the static correction modes are not
  /// eigenvectors and their residuals are what they are.
  Eigen::VectorXd relative_residuals, residual_floors;
  Eigen::MatrixXd vectors;         ///< 3 n_n x n_m, M̄-orthonormal, node-interleaved
  Eigen::Index normal_modes = 0;   ///< the first this many are eigenmodes, the rest static corrections
  StaticCorrectionStats static_correction;
  double shift = 0.0;
  /// max_k ||K r_k|| / (||K||_1 ||r_k||) over the six M̄-orthonormal rigid-body fields r_k.
  double rigid_body_residual = 0.0;
  /// max_k |r_kᵀ M̄ phi| over rigid fields and elastic modes (0 up to round-off).
  double rigid_body_coupling = 0.0;
  int solver_runs = 0;
  int restarts = 0;
  int operator_applies = 0;
  EigensolverBackend eigensolver = EigensolverBackend::arpack;  ///< the backend of the last run (never automatic)
  ShiftSolveStats stats;
  /// With `prestress_loads`: their static responses with inertia relief (3 n_n x p, static_correction.hpp:
  /// relieved_static_responses against the rigid-body fields), solved on the modes' factorization, and how the
  /// solves went.
  Eigen::MatrixXd prestress_responses;
  StaticCorrectionStats prestress;
};

/// Computes the lowest elastic free-free modes of K̄ phi = omega^2 M̄ phi (M̄ = M_s ⊗ I3) by shift-invert
/// on a CHOLMOD factorization of K̄ - sigma M̄ with sigma < 0, the six rigid-body modes deflated.
/// With `static_loads` (3 n_n x s nodal force vectors, e.g. unit_load_vectors), the basis is extended by
/// their residual static correction modes (inertia relief; static_correction.hpp) on the same factorization.
/// With `prestress_loads` (3 n_n x p), their relieved static responses too (FreeFreeModes::prestress_responses; the
/// geometric stiffness's load cases, geometric_stiffness.hpp, named in errors by `prestress_names`), on the same
/// factorization.
/// Throws std::runtime_error when the body has more than six zero-energy modes (a mechanism or a
/// disconnected mesh), when a normal mode's residual exceeds max(1e-8, kResidualFloorFactor x its rounding
/// floor) (eigen_residual.hpp: not converged), or when a solver fails.
[[nodiscard]] FreeFreeModes free_free_modes(const RowMatrixX3d& nodes, const SparseMatrix& stiffness_upper,
                                            const SparseMatrix& scalar_mass_upper, const Material& material,
                                            const FreeFreeOptions& options,
                                            const Eigen::MatrixXd& static_loads = Eigen::MatrixXd(),
                                            const Eigen::MatrixXd& prestress_loads = Eigen::MatrixXd(),
                                            const std::vector<std::string>& prestress_names = {});

/// The automatic shift of FreeFreeOptions::shift for a body of this size and material.
[[nodiscard]] double automatic_shift(const RowMatrixX3d& nodes, const Material& material);

/// Converts node-interleaved modes (3 n_n x n_m) into Ῡ of Eq. (49): n_n x 3 n_m, row i =
/// [psi_1^(i)T ... psi_nm^(i)T].
[[nodiscard]] Eigen::MatrixXd upsilon_from_modes(const Eigen::MatrixXd& modes);

}  // namespace flexbody::preprocess
