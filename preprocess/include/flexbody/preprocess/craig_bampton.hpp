#pragma once
// flexbody/preprocess/craig_bampton.hpp: Craig-Bampton reduction of a free body with rigid (rbe2)
// interfaces, orthonormalised as Adams and Altair do: fixed-interface normal modes (every interface
// clamped) plus 6 constraint modes per interface (the static response to a unit rigid motion of one
// interface with the others clamped), then the reduced eigenproblem on that basis, whose 6 rigid-body
// vectors are dropped. The result spans the same space minus the rigid motions, M̄-orthonormal and
// M̄-orthogonal to the rigid-body fields, so the translational Tisserand constraint holds identically.

#include "flexbody/preprocess/eigensolver.hpp"
#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/shift_invert_operator.hpp"
#include "flexbody/preprocess/static_correction.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <vector>

namespace flexbody::preprocess {

// RigidInterface (one rbe2 interface) is declared in interfaces.hpp: the static solves share it.

struct CraigBamptonOptions {
  /// Normal modes with every interface clamped; 0 = not set (then fmax_hz decides).
  int fixed_interface_modes = 8;
  /// All fixed-interface modes up to this frequency [Hz]; 0 = not set. With both, the count caps.
  double fmax_hz = 0.0;
  EigensolverOptions solver;
  double shift = 0.0;  ///< sigma < 0 for the clamped eigenproblem; 0 = automatic_shift
};

struct CraigBamptonModes {
  /// The clamped problem: omega^2 [rad^2/s^2], frequencies, ||K φ - ω² M φ||_2 / ||K φ||_2 and its rounding
  /// floor (eigen_residual.hpp; each residual is at most max(1e-8, kResidualFloorFactor x its floor)).
  Eigen::VectorXd fixed_interface_eigenvalues, fixed_interface_frequencies_hz, fixed_interface_residuals,
      fixed_interface_residual_floors;
  /// The Craig-Bampton basis before orthonormalisation: [fixed-interface modes, constraint modes, static
  /// corrections] (3 n_n x (n_fixed + 6 n_interfaces + n_static)); constraint mode 6 j + k moves interface j
  /// by unit DOF k (translations x, y, z, then small rotations about x, y, z); the static corrections are
  /// the clamped body's residual responses to the static loads (zero on the interfaces).
  Eigen::MatrixXd basis;
  StaticCorrectionStats static_correction;
  /// The orthonormalised elastic modes (3 n_n x (n_fixed + 6 n_interfaces + n_static - 6)): M̄-orthonormal,
  /// M̄-orthogonal to the rigid-body fields, ascending in omega^2.
  Eigen::VectorXd eigenvalues, frequencies_hz;
  /// ||K̄ψ − ω²M̄ψ|| / ||K̄ψ|| of each orthonormalised mode in the tied model (interior nodal forces, and
  /// per interface the resultant force and moment): how far it is from an eigenmode of the free body with
  /// rigid interfaces (Craig-Bampton modes are not eigenmodes; this measures the reduction error).
  Eigen::VectorXd relative_residuals;
  Eigen::MatrixXd vectors;
  double rigid_body_coupling = 0.0;  ///< max |r_kᵀ M̄ ψ| over the rigid fields r_k and the modes
  double shift = 0.0;
  EigensolverBackend eigensolver = EigensolverBackend::arpack;  ///< the backend of the last run (never automatic)
  ShiftSolveStats stats;
};

/// `static_loads` (3 n_n x s nodal force vectors, e.g. unit_load_vectors, zero on the interfaces) add their
/// static responses with every interface clamped, less what the fixed-interface modes hold, to the basis.
/// Throws std::invalid_argument for no interface or an impossible mode count, std::runtime_error when
/// a fixed-interface mode's residual exceeds max(1e-8, kResidualFloorFactor x its rounding floor)
/// (eigen_residual.hpp: not converged), the reduced problem does not have exactly six
/// zero-energy vectors (a mechanism) or a solver fails.
[[nodiscard]] CraigBamptonModes craig_bampton_modes(const RowMatrixX3d& nodes, const SparseMatrix& stiffness_upper,
                                                    const SparseMatrix& scalar_mass_upper, const Material& material,
                                                    const std::vector<RigidInterface>& interfaces,
                                                    const CraigBamptonOptions& options,
                                                    const Eigen::MatrixXd& static_loads = Eigen::MatrixXd());

}  // namespace flexbody::preprocess
