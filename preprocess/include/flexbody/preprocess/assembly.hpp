#pragma once
// flexbody/preprocess/assembly.hpp: global stiffness K̄ and scalar mass M_s of a tet4 mesh.
//
// Both are assembled column by column in parallel (OpenMP): each thread owns whole node columns
// and sums the element contributions of the elements around that node in element order, so the
// result is bit-for-bit the same for any thread count, and no atomics are needed.

#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/tet4_element.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <vector>

namespace flexbody::preprocess {

/// Node-to-node adjacency of a mesh, upper part: for node j, the sorted nodes i <= j that share an
/// element with j (j itself last), plus the node-to-element incidence used by the assembly.
struct NodeGraph {
  std::vector<std::int64_t> column_start;  ///< n_n + 1 offsets into `rows`
  std::vector<std::int32_t> rows;          ///< neighbours i <= j of each node j, sorted
  std::vector<std::int64_t> incidence_start;  ///< n_n + 1 offsets into `incidence`
  std::vector<std::int64_t> incidence;        ///< p e + a for element e whose local node a is j (p nodes per element)

  [[nodiscard]] static NodeGraph build(const TetMesh& mesh);
  [[nodiscard]] static NodeGraph build(const Tet10Mesh& mesh);  ///< quadratic tetrahedra: p = 10
};

/// The empty upper-triangle patterns the graph gives: the scalar one (n_n square, as M_s) and the node-interleaved
/// one (3 n_n square, as K̄: DOF column 3 j + c holds rows 3 i .. 3 i + 2 of each neighbour i < j, then rows 3 j ..
/// 3 j + c, so entry (3 i + r, 3 j + c) of the k-th neighbour sits at outerIndexPtr()[3 j + c] + 3 k + r).
[[nodiscard]] SparseMatrix scalar_pattern(const NodeGraph& graph);
[[nodiscard]] SparseMatrix vector_pattern(const NodeGraph& graph);
/// Index k of node i (<= j) within the sorted upper column of node j.
[[nodiscard]] std::int64_t position_in_column(const NodeGraph& graph, std::int64_t j, std::int32_t i);

/// Volumes and gradients of every element (computed in parallel).
[[nodiscard]] std::vector<Tet4Geometry> element_geometries(const TetMesh& mesh);

/// Linear-elastic stiffness K̄ (3 n_n square, node-interleaved DOFs x0 y0 z0 x1 ..., upper triangle).
[[nodiscard]] SparseMatrix assemble_stiffness(const TetMesh& mesh, const NodeGraph& graph,
                                              const std::vector<Tet4Geometry>& geometry,
                                              const Material& material);

/// Scalar mass M_s (n_n square, upper triangle); the DOF mass matrix is M̄ = M_s ⊗ I3.
[[nodiscard]] SparseMatrix assemble_scalar_mass(const TetMesh& mesh, const NodeGraph& graph,
                                                const std::vector<Tet4Geometry>& geometry,
                                                double density, MassScheme scheme);

/// y = (M_s ⊗ I3) x for node-interleaved vectors x, y of length 3 n_n (M_s stored upper); x and y must
/// not overlap.
void apply_vector_mass(const SparseMatrix& scalar_mass_upper, const Eigen::Ref<const Eigen::VectorXd>& x,
                       Eigen::Ref<Eigen::VectorXd> y);

/// Y = A X for a symmetric A stored whole (both triangles, as full_from_upper gives it), the rows on all threads:
/// row j of Y from column j of A. Eigen's product with the upper triangle alone runs on one thread (1.0 s for M_s
/// times 78 fields at 1M DOFs).
[[nodiscard]] Eigen::MatrixXd symmetric_product(const SparseMatrix& full, const Eigen::Ref<const Eigen::MatrixXd>& x);

/// y = K x for K stored as its upper triangle.
void apply_symmetric(const SparseMatrix& upper, const Eigen::Ref<const Eigen::VectorXd>& x,
                     Eigen::Ref<Eigen::VectorXd> y);

}  // namespace flexbody::preprocess
