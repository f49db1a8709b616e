#pragma once
// flexbody/preprocess/tet_mesh.hpp: the tetrahedral mesh and the sparse matrix type of the pipeline.

#include "flexbody/format/body_data.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <cstdint>

namespace flexbody::preprocess {

using format::RowMatrixX3d;
using format::RowMatrixX3i;
using format::RowMatrixX4i;

/// Sparse symmetric matrices are stored as their UPPER triangle in compressed columns with 64-bit
/// indices, the layout CHOLMOD's cholmod_l_* interface reads without a copy (stype = +1).
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, std::int64_t>;

/// A linear tetrahedral mesh. Node coordinates in metres; tets positively oriented
/// (det[x1-x0, x2-x0, x3-x0] > 0), 0-based node indices.
struct TetMesh {
  RowMatrixX3d nodes;
  RowMatrixX4i tets;

  [[nodiscard]] Eigen::Index node_count() const { return nodes.rows(); }
  [[nodiscard]] Eigen::Index element_count() const { return tets.rows(); }
  [[nodiscard]] Eigen::Index dof_count() const { return 3 * nodes.rows(); }
};

/// A quadratic tetrahedral mesh: per element its 4 corners, then the middles of the edges (0,1), (1,2),
/// (2,0), (0,3), (1,3), (2,3) (format/tet10_element.hpp). Node coordinates in metres, 0-based indices.
struct Tet10Mesh {
  RowMatrixX3d nodes;
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, 10, Eigen::RowMajor> tets;

  [[nodiscard]] Eigen::Index node_count() const { return nodes.rows(); }
  [[nodiscard]] Eigen::Index element_count() const { return tets.rows(); }
  [[nodiscard]] Eigen::Index dof_count() const { return 3 * nodes.rows(); }
};

/// Corner coordinates of tetrahedron e (row a = node a).
[[nodiscard]] inline Eigen::Matrix<double, 4, 3> element_corners(const TetMesh& mesh, Eigen::Index e) {
  Eigen::Matrix<double, 4, 3> corners;
  for (int a = 0; a < 4; ++a) corners.row(a) = mesh.nodes.row(mesh.tets(e, a));
  return corners;
}

/// The full symmetric matrix from its stored upper triangle (for tests and small problems).
[[nodiscard]] SparseMatrix full_from_upper(const SparseMatrix& upper);

}  // namespace flexbody::preprocess
