#pragma once
// flexbody/preprocess/mesh_topology.hpp: checks and derived topology of a tetrahedral mesh.

#include "flexbody/preprocess/tet_mesh.hpp"

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
};
[[nodiscard]] double radius_ratio(const Eigen::Matrix<double, 4, 3>& corners);
[[nodiscard]] MeshQuality mesh_quality(const TetMesh& mesh);

}  // namespace flexbody::preprocess
