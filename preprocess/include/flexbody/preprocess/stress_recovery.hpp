#pragma once
// flexbody/preprocess/stress_recovery.hpp: nodal stresses of linear (and quadratic) tetrahedra, of displacement fields and of
// the GCMS fields (the stress modes S of an output region, formats/SCHEMA.md section Recovery).
//
// A linear tetrahedron has constant strain: for a displacement u, H_e = Σ_a u_a ⊗ ∇N_a (∇N_a from
// tet4_geometry), ε = ½ (H + Hᵀ), and the isotropic Hooke law gives σ = λ tr(ε) I + 2 μ ε with
// λ = E ν / ((1 + ν)(1 − 2 ν)) and μ = E / (2 (1 + ν)) (lame_lambda, shear_modulus). Nodal values are the
// volume-weighted average over the elements around a node, σ_i = Σ_{e ∋ i} V_e σ_e / Σ_{e ∋ i} V_e, the usual
// nodal averaging of FE post-processors. σ is linear in H, so this equals σ of the averaged gradient
// H̄_i = Σ_b u_b ⊗ w_ib with w_ib = Σ_{e ∋ i, b} V_e ∇N_b^e / Σ_{e ∋ i} V_e over the neighbours b of i: that is
// how it is computed (one small operator per node, applied to every column), in parallel over nodes (OpenMP),
// each output row written by one thread in a fixed order: bit-identical results for any thread count.
//
// Every function throws std::invalid_argument naming the problem for wrong sizes, node indices out of range,
// non-finite values, an invalid material, a node that belongs to no element, or an element around an output
// node whose volume is not positive.

#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <Eigen/Core>

namespace flexbody::preprocess {

/// Voigt order of every stress here: xx, yy, zz, xy, xz, yz (Abaqus S11, S22, S33, S12, S13, S23).
/// Shear entries are the tensor components σ_xy etc. (not engineering strains: there are none here).
inline constexpr int kStressComponents = 6;

/// Nodal stresses [Pa] of node-interleaved displacement fields (3 n_n x m, metres): returns 6 n_n x m, row 6 i + c =
/// component c at node i. Linear tetrahedra have constant strain; the element stresses σ = λ tr(ε) I + 2 μ ε are
/// averaged to each node weighted by the volumes of all elements around it (the usual nodal averaging).
/// Columns are independent: column k of the result depends on column k of `displacements` only (bit for bit).
/// Every node must belong to an element. For a displacement field in units other than metres (e.g. an
/// M-normalised mode, kg^-1/2) the result is in Pa per that unit.
[[nodiscard]] Eigen::MatrixXd nodal_stresses(const TetMesh& mesh, const Material& material,
                                             const Eigen::MatrixXd& displacements);

/// Stress modes of scalar nodal fields (n_n x n_f), e.g. the GCMS fields Ῡ': column 3 f + d of the result is the
/// nodal stress of the displacement field fields.col(f) ⊗ e_d (d = x, y, z), at the nodes `region_nodes` only:
/// 6 k x 3 n_f, row 6 j + c = component c at node region_nodes(j). Same nodal averaging as nodal_stresses (over ALL
/// elements around a region node, not only those inside a region). Units: Pa per metre of displacement times the
/// field's unit; for Ῡ' [kg^-1/2] that is Pa kg^-1/2 m^-1, the stress per unit field coordinate ξ [m kg^1/2], as
/// SCHEMA.md stores S. Region nodes may come in any order and may repeat; only the elements around them are
/// evaluated, so the cost grows with k and n_f (memory: the result, plus O(n_n + n_e) integers).
/// \code
///   const Eigen::MatrixXd s = nodal_stress_modes(mesh, steel, body.gcms.fields, region.nodes);
///   const Eigen::VectorXd sigma = s * xi_body;  // 6 k stresses [Pa] for body-frame field coordinates ξ̄
/// \endcode
[[nodiscard]] Eigen::MatrixXd nodal_stress_modes(const TetMesh& mesh, const Material& material,
                                                 const Eigen::MatrixXd& fields, const Eigen::VectorXi& region_nodes);

/// The same for quadratic tetrahedra: each element's stress at its node is extrapolated from its 4 Gauss
/// points (format::tet10_recovery_gradients: exact in straight-sided elements, whose stress is linear), then averaged
/// over the elements around the node weighted by their volumes. A quadratic displacement field gives its exact
/// (linear) stress at every node of a straight-sided mesh.
[[nodiscard]] Eigen::MatrixXd nodal_stresses(const Tet10Mesh& mesh, const Material& material,
                                             const Eigen::MatrixXd& displacements);
[[nodiscard]] Eigen::MatrixXd nodal_stress_modes(const Tet10Mesh& mesh, const Material& material,
                                                 const Eigen::MatrixXd& fields, const Eigen::VectorXi& region_nodes);

/// Von Mises equivalent stress [Pa] of one Voigt stress vector (order above):
/// sqrt(½ [(σxx − σyy)² + (σyy − σzz)² + (σzz − σxx)²] + 3 (σxy² + σxz² + σyz²)).
[[nodiscard]] double von_mises(const Eigen::Matrix<double, 6, 1>& stress);

}  // namespace flexbody::preprocess
