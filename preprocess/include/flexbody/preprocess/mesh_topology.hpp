#pragma once
// flexbody/preprocess/mesh_topology.hpp: checks and derived topology of a tetrahedral mesh.

#include "flexbody/preprocess/tet_mesh.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace flexbody::preprocess {

/// Connected components of the mesh (elements connected through shared nodes): component index of
/// every node, and the number of components. Nodes used by no element get component -1.
struct MeshComponents {
  std::vector<std::int32_t> node_component;
  int count = 0;
};
[[nodiscard]] MeshComponents connected_components(const TetMesh& mesh);

/// Drops nodes no element uses and renumbers the rest in their original order. Returns the new index
/// of every old node (-1 for a dropped one).
std::vector<std::int32_t> remove_unused_nodes(TetMesh& mesh);

/// Throws std::runtime_error naming the first element with zero or negative volume (relative to the
/// mesh's size), and how many such elements there are. `source` prefixes the message.
void check_element_volumes(const TetMesh& mesh, const std::string& source);

/// The boundary triangles: faces used by exactly one tetrahedron, oriented counter-clockwise seen
/// from outside (outward normal by the right-hand rule).
[[nodiscard]] RowMatrixX3i boundary_triangles(const TetMesh& mesh);

/// The boundary of a quadratic mesh: each 6-node face (corners a, b, c, edge nodes m_ab, m_bc, m_ca) as its four
/// triangles (a, m_ab, m_ca), (m_ab, b, m_bc), (m_ca, m_bc, c), (m_ab, m_bc, m_ca), oriented like the face
/// (formats/SCHEMA.md, Mesh), so every boundary node is a triangle's corner.
[[nodiscard]] RowMatrixX3i boundary_triangles(const Tet10Mesh& mesh);

/// The four triangles of one 6-node triangle given as (a, b, c, m_ab, m_bc, m_ca), in the order above.
[[nodiscard]] std::array<std::array<std::int32_t, 3>, 4> split_quadratic_triangle(const std::array<std::int32_t, 6>& face);

/// The linear mesh of a quadratic one's corners (same corner indices, every node kept).
[[nodiscard]] TetMesh corner_mesh(const Tet10Mesh& mesh);

/// Element quality by the normalized radius ratio q = 3 r_in / r_circ (1 for the regular tetrahedron,
/// 0 for a degenerate one).
struct MeshQuality {
  double min_radius_ratio = 0.0;
  double mean_radius_ratio = 0.0;
  std::int64_t worst_element = -1;
  std::int64_t below_0_1 = 0;  ///< elements with q < 0.1 (slivers)
  std::int64_t below_0_3 = 0;  ///< elements with q < 0.3
  double min_edge_m = 0.0;
  double max_edge_m = 0.0;
  double volume_m3 = 0.0;
  /// Quadratic meshes: the smallest ratio min / max of an element's Jacobian determinant over its 4 Gauss points and
  /// 10 nodes (1 for a straight-sided element, <= 0 for a folded one), and that element. Linear meshes: 1 and -1.
  double min_jacobian_ratio = 1.0;
  std::int64_t worst_jacobian_element = -1;
};
[[nodiscard]] double radius_ratio(const Eigen::Matrix<double, 4, 3>& corners);
[[nodiscard]] MeshQuality mesh_quality(const TetMesh& mesh);
/// The quality of a quadratic mesh: radius ratios and edges of its corners' straight tetrahedra, the Jacobian ratio,
/// and the volume by the 4-point Gauss rule (exact for straight-sided elements).
[[nodiscard]] MeshQuality mesh_quality(const Tet10Mesh& mesh);

}  // namespace flexbody::preprocess
