#pragma once
// full_order_mesh.hpp (internal): the pieces of the full-order body of a body file (full_order.hpp): its mesh's
// K̄ and M_s, the shared fields of its rbe2 node sets, and its interfaces as markers in those fields.

#include "flexbody/format/body_data.hpp"
#include "flexbody/runtime/body_model.hpp"

#include <Eigen/SparseCore>

#include <string>
#include <vector>

namespace flexbody::runtime {

struct AssembledMesh {
  Eigen::SparseMatrix<double> stiffness;    ///< K̄ (3 n_n square, node-interleaved, both triangles) [N/m]
  Eigen::SparseMatrix<double> scalar_mass;  ///< consistent M_s (n_n square, both triangles) [kg]
};

/// K̄ and M_s of the mesh's linear or quadratic tetrahedra for the material, summed element by element as fbprep does
/// (preprocess/assembly.hpp, tet10_assembly.hpp) from the same element integrals (format/tet4_element.hpp,
/// tet10_element.hpp). Throws std::invalid_argument naming the element for one that is inverted, flat or folded.
[[nodiscard]] AssembledMesh assemble_mesh(const format::BodyMesh& mesh, const format::Material& material,
                                          const std::string& source);

/// T (n_n x n_f) of the rbe2 interfaces' affine node sets: a unit field for each node outside them, then per rbe2
/// interface the independent ones of 1 and (X̄ − X̄_c)/ρ (ρ the set's radius, so every entry is at most 1 in size)
/// over its nodes: 4, or 3 for a flat set. Empty (Ῡ' = I) when there is no rbe2 interface. Throws
/// std::invalid_argument if two rbe2 interfaces share a node.
[[nodiscard]] Eigen::SparseMatrix<double, Eigen::RowMajor> affine_node_sets(const format::RowMatrixX3d& nodes,
                                                                           const std::vector<format::Interface>& interfaces,
                                                                           const std::string& source);

/// The interface as a marker of the full-order body `model`: y_row = Σ_i w_i [1, X̄_i, Ῡ'_i] and the rotation R of the
/// weighted least-squares rigid fit of its nodes' displacements, H θ̄ = Σ_i w_i d_i × u_i with
/// H = Σ_i w_i (|d_i|² I − d_i d_iᵀ), d_i = X̄_i − X̄_c (SCHEMA.md /interfaces, as fbprep computes it for modes).
[[nodiscard]] format::Interface full_order_interface(const format::Interface& interface, const BodyModel& model,
                                                     const std::string& source);

}  // namespace flexbody::runtime
