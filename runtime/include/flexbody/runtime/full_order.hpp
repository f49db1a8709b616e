#pragma once
// flexbody/runtime/full_order.hpp: the unreduced improved ACF as a reference body (formulations.md, "The Method": the
// constant core: the same structure with Ῡ = I, so ξ are the nodal displacements, K̂ = K̄ and G_ff = M_s). It measures
// what a reduced body's modes leave out. Sparse: K̄ and M_s keep the mesh's sparsity (BodyModel::sparse), its constant
// Newton core M_s ⊗ I3 + K̄/β' is factorized once by Eigen's sparse Cholesky, and each iteration costs products with the
// mesh's matrices. Its fields are not M-orthogonal to the rigid motions, so the body also carries the
// translational Tisserand rows (Eq. 77). Its damping can only be stiffness-proportional (damp_full_order), which
// keeps the core sparse.
//
// From a body file (fbsim's `modes: full`), K̄ and M_s are assembled again from the file's mesh and material. An rbe2
// interface then ties its nodes to move affinely, u_i = c + B X̄_i: over its node set each displacement component is a
// combination of 1 and X̄, which is exactly the span the improved GCMS's Craig-Bampton fields have there (each field is
// one component of modes that move the set rigidly, so it is affine over the set). The body is therefore the limit the
// reduced GCMS bodies of the file converge to as modes are added. It is not a rigid patch: the affine map has 12
// freedoms where a rigid one has 6, and holding the other 6 would take constraints nonlinear in the coordinates.
// Those nodes then share their fields: Ῡ' = T (SparseFieldBlocks::fields) instead of I.

#include "flexbody/runtime/body_model.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace flexbody::runtime {

/// The full-order body of a mesh: K̄ (3 n_n square, node-interleaved) and the scalar mass M_s (n_n square), both
/// symmetric with both triangles stored, and the node positions X̄ in the body frame (origin at the centre of mass).
/// Throws std::invalid_argument for inconsistent sizes or a mesh whose centre of mass is not at the origin.
[[nodiscard]] BodyModel full_order_model(const Eigen::SparseMatrix<double>& stiffness,
                                         const Eigen::SparseMatrix<double>& scalar_mass,
                                         const format::RowMatrixX3d& nodes, const std::string& source = "full order");

/// The full-order body of a body file: K̄ and the consistent M_s of its linear or quadratic tetrahedra
/// (format/tet4_element.hpp, tet10_element.hpp: fbprep's element integrals) from
/// /mesh and /material, its rbe2 interfaces as affine node sets and all its interfaces as markers (y_row and the
/// rigid-fit rotation R in the body's fields). It has no output regions: stresses are recovered from modes, and the
/// file's stress modes have no full-order counterpart. Throws std::invalid_argument naming `source` for an element order
/// other than 1 and 2, an inverted, flat or folded element, or rbe2 interfaces that share nodes.
[[nodiscard]] BodyModel full_order_model(const format::BodyData& body, const std::string& source = "body");

/// The full-order body with stiffness-proportional damping D̂ = β K̄ [β in s] of its deformation: mode m of the mesh
/// gets the ratio β ω_m / 2, as a reduced body with rayleigh_damping(model, 0, β) does for its modes, so that a
/// damped reduced body and its reference damp alike. Throws std::invalid_argument for a model that is not full-order
/// or a negative or non-finite β.
[[nodiscard]] BodyModel damp_full_order(BodyModel model, double beta);

}  // namespace flexbody::runtime
