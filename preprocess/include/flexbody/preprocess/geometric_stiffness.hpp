#pragma once
// flexbody/preprocess/geometric_stiffness.hpp: the geometric (stress) stiffness of unit prestress load cases, projected
// onto the GCMS fields (formulations.md, "Geometric Stiffening").
//
// A part that spins or carries joint loads is prestressed, and the prestress σ stiffens it (tension) or softens it
// (compression) through the second-order strain energy ½ ∫ σ_ij u_k,i u_k,j dV. A linear corotational model has no
// such term. σ is linear in the loads, so the geometric stiffness is computed once per unit load case k and weighted
// at run time, K_σ(t) = Σ_k λ_k(t) K_σ,k (Wallrapp's SID "second-order terms"; Banerjee & Dickens 1990). It acts alike
// on the three displacement components, K_σ = S ⊗ I3 with the scalar S_ab = ∫ ∇N_aᵀ σ ∇N_b dV, so its projection onto
// the fields Y = [1, X̄, Ῡ'] of G is Ĝ_σ = Yᵀ S Y, (4 + n_f) square: the GCMS's K̂ (Eq. 96) gains
// (Ĝ_σ[4:, 4:] ⊗ I3) λ_k, and a floating-frame body's modes, combinations of these fields, project it as they do G.
// Row and column 0 (the constant field, no gradient) are zero up to round-off.
//
// The load cases of a free part, each balanced by the rigid-body accelerations it causes (inertia relief,
// static_correction.hpp: relieved_static_responses):
//  - centrifugal:xx, :yy, :zz, :xy, :xz, :yz: the centrifugal force field of a spin ω about the centre of mass,
//    ρ (|ω|² I − ω ωᵀ) x̄ = Σ_k λ_k ρ ((tr W_k) I − W_k) x̄ with λ = (ω_x², ω_y², ω_z², ω_x ω_y, ω_x ω_z, ω_y ω_z)
//    [rad²/s²] and W_k = e_i e_iᵀ (i = j) or e_i e_jᵀ + e_j e_iᵀ (i ≠ j), so that Σ_k λ_k W_k = ω ωᵀ;
//  - <interface>:fx ... :mz: a unit force [N] and a unit moment [N m] at each interface, spread over its nodes as an
//    rbe3 element does (static_correction.hpp: unit_load_vectors).
// A uniform frame acceleration (gravity among them) or an angular acceleration is a rigid-body field M̄ R β: inertia
// relief balances it entirely, so it causes no prestress of its own; the joint reactions that cause the acceleration
// do, through the interface cases. What the cases leave out: loads elsewhere than at interfaces (a force on a node or
// a point), the change of the modes with the prestress (a fixed basis), and large deformation.

#include "flexbody/format/body_data.hpp"
#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace flexbody::preprocess {

/// The centrifugal load cases' names after "centrifugal:", in the order of their columns and weights λ.
inline constexpr const std::array<const char*, 6>& kCentrifugalCases = format::kCentrifugalCases;

/// The six centrifugal unit loads: nodal forces (3 n_n x 6, node-interleaved) [N per rad²/s²] of the body-frame nodes
/// (origin at the centre of mass), column k = M̄ ((tr W_k) I − W_k) x̄ (the consistent nodal forces of the body force,
/// exact for the mesh). Throws std::invalid_argument for sizes that differ.
[[nodiscard]] Eigen::MatrixXd centrifugal_unit_loads(const RowMatrixX3d& body_nodes, const SparseMatrix& scalar_mass_upper);

/// Ĝ_σ = Yᵀ S Y for the prestress of each displacement field (3 n_n x p, node-interleaved, metres per unit load: the
/// static responses of the cases), Y = `fields` (n_n x c, e.g. [1, X̄, Ῡ']): p symmetric c x c matrices. σ is that of
/// the isotropic material, integrated as K̄ is (linear tetrahedra: one point, exact; quadratic: the 4-point rule), so
/// that for an affine field Y = X̄_i the entry (X̄_i, X̄_j) is Σ_nodes x̄_i f_j of the load the field balances (the
/// virtual work of the displacement x̄_i e_j, exact). Cases run in parallel (OpenMP), each summed in element order:
/// bit-identical results for any thread count. Throws std::invalid_argument for sizes that differ or non-finite input.
[[nodiscard]] std::vector<Eigen::MatrixXd> projected_geometric_stiffness(const TetMesh& mesh, const Material& material,
                                                                         const Eigen::MatrixXd& displacements,
                                                                         const Eigen::MatrixXd& fields);
[[nodiscard]] std::vector<Eigen::MatrixXd> projected_geometric_stiffness(const Tet10Mesh& mesh, const Material& material,
                                                                         const Eigen::MatrixXd& displacements,
                                                                         const Eigen::MatrixXd& fields);

}  // namespace flexbody::preprocess
