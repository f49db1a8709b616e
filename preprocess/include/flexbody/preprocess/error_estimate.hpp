#pragma once
// flexbody/preprocess/error_estimate.hpp: how far a mesh's frequencies are from the part's.
//
// The Zienkiewicz-Zhu estimate (ZZ 1987): the recovered stress σ* (the nodal averages of stress_recovery.hpp,
// interpolated by the element's shape functions) is closer to the exact stress than the element's own σ_h, so
// η² = Σ_e ∫_e (σ* − σ_h) : C⁻¹ (σ* − σ_h) dV estimates the energy norm of the error. For an M-normalised mode with
// eigenvalue λ_h = ω_h², λ_h − λ ≈ ‖u − u_h‖²_K (the eigenvalue error of a conforming FE mesh is the error's
// energy, to second order), so the exact eigenvalue is about λ_h − η² and the frequency f_h √(1 − η²/λ_h): the
// relative frequency error is estimated as (1 − η²/λ_h)^(−1/2) − 1. Linear tetrahedra have constant σ_h; σ* is
// linear over each element and the integral is exact (∫ N_a N_b dV = V (1 + δ_ab) / 20). Quadratic ones compare
// the two at the 4 Gauss points.

#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <Eigen/Core>

namespace flexbody::preprocess {

/// The estimate of each mode and where its error lies.
struct FrequencyErrorEstimate {
  /// Each mode's estimated relative frequency error f_h / f − 1 (as frequency_error_estimates).
  Eigen::VectorXd relative;
  /// Each element's share of the relative eigenvalue error, the largest over the modes: max_k η²_{e,k} / λ_k
  /// (dimensionless; Σ_e of one mode's shares is its estimated relative eigenvalue error). Drives the refinement of
  /// mesh_refinement.hpp.
  Eigen::VectorXd element_shares;
};
[[nodiscard]] FrequencyErrorEstimate estimate_frequency_errors(const TetMesh& mesh, const Material& material,
                                                               const Eigen::MatrixXd& modes,
                                                               const Eigen::VectorXd& frequencies_hz);
[[nodiscard]] FrequencyErrorEstimate estimate_frequency_errors(const Tet10Mesh& mesh, const Material& material,
                                                               const Eigen::MatrixXd& modes,
                                                               const Eigen::VectorXd& frequencies_hz);

/// Each mode's estimated relative frequency error f_h / f − 1 (≥ 0; +inf when the estimated error energy reaches the
/// eigenvalue: the mesh does not resolve that mode at all), for M-normalised mode shapes (3 n_n x m, node-interleaved)
/// with frequencies [Hz] (m). Modes at zero frequency (rigid-body) get 0.
[[nodiscard]] Eigen::VectorXd frequency_error_estimates(const TetMesh& mesh, const Material& material,
                                                        const Eigen::MatrixXd& modes,
                                                        const Eigen::VectorXd& frequencies_hz);
/// The same for quadratic tetrahedra: σ_h and σ* = Σ N_a σ*_a (the nodal stresses extrapolated from the Gauss points
/// and averaged, stress_recovery.hpp) compared at the elements' 4 Gauss points (the stiffness's rule).
[[nodiscard]] Eigen::VectorXd frequency_error_estimates(const Tet10Mesh& mesh, const Material& material,
                                                        const Eigen::MatrixXd& modes,
                                                        const Eigen::VectorXd& frequencies_hz);

}  // namespace flexbody::preprocess
