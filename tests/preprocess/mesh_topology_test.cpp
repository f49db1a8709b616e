// Mesh checks and derived topology: orientation, connectivity, boundary surface, element quality.
#include "flexbody/preprocess/mesh_topology.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

namespace fp = flexbody::preprocess;
using flexbody::test::box_mesh;

TEST(MeshTopology, BoxBoundaryIsClosedAndOutward) {
  const fp::TetMesh mesh = box_mesh(2.0, 1.0, 0.5, 4, 3, 2);
  const fp::RowMatrixX3i triangles = fp::boundary_triangles(mesh);
  // Each boundary cell face is split into 2 triangles.
  EXPECT_EQ(triangles.rows(), 2 * 2 * (4 * 3 + 4 * 2 + 3 * 2));
  // Divergence theorem: V = 1/3 sum over triangles of (area normal) . centroid, exact for outward faces.
  double volume = 0.0;
  for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
    const Eigen::Vector3d a = mesh.nodes.row(triangles(t, 0)), b = mesh.nodes.row(triangles(t, 1)),
                          c = mesh.nodes.row(triangles(t, 2));
    volume += 0.5 * (b - a).cross(c - a).dot((a + b + c) / 3.0) / 3.0;
  }
  EXPECT_NEAR(volume, 1.0, 1e-14);
}

TEST(MeshTopology, KuhnBoxHasPositiveElementsAndOneComponent) {
  const fp::TetMesh mesh = box_mesh(1.0, 1.0, 1.0, 3, 3, 3);
  EXPECT_NO_THROW(fp::check_element_volumes(mesh, "box"));
  EXPECT_EQ(fp::connected_components(mesh).count, 1);
}

TEST(MeshTopology, DetectsInvertedElementAndNamesIt) {
  fp::TetMesh mesh = box_mesh(1.0, 1.0, 1.0, 2, 2, 2);
  std::swap(mesh.tets(5, 1), mesh.tets(5, 2));
  try {
    fp::check_element_volumes(mesh, "part.msh");
    FAIL() << "no error for an inverted element";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("part.msh: 1 inverted or zero-volume element, first is tetrahedron 5"),
              std::string::npos)
        << e.what();
  }
}

TEST(MeshTopology, CountsDisconnectedComponents) {
  fp::TetMesh a = box_mesh(1.0, 1.0, 1.0, 1, 1, 1);
  fp::TetMesh two;
  two.nodes.resize(2 * a.node_count(), 3);
  two.nodes << a.nodes, (a.nodes.rowwise() + Eigen::RowVector3d(3.0, 0.0, 0.0));
  two.tets.resize(2 * a.element_count(), 4);
  two.tets << a.tets, (a.tets.array() + static_cast<std::int32_t>(a.node_count())).matrix();
  EXPECT_EQ(fp::connected_components(two).count, 2);
}

TEST(MeshTopology, RadiusRatioIsOneForRegularTetrahedronAndSmallForSliver) {
  Eigen::Matrix<double, 4, 3> regular;
  regular << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1;
  EXPECT_NEAR(fp::radius_ratio(regular), 1.0, 1e-14);
  Eigen::Matrix<double, 4, 3> sliver;  // four nearly coplanar points
  sliver << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 1e-3;
  EXPECT_LT(fp::radius_ratio(sliver), 0.01);
}

TEST(MeshTopology, RemovesUnusedNodesKeepingOrder) {
  fp::TetMesh mesh;
  mesh.nodes.resize(6, 3);
  mesh.nodes << 9, 9, 9, 0, 0, 0, 1, 0, 0, 7, 7, 7, 0, 1, 0, 0, 0, 1;
  mesh.tets.resize(1, 4);
  mesh.tets << 1, 2, 4, 5;
  fp::remove_unused_nodes(mesh);
  ASSERT_EQ(mesh.node_count(), 4);
  EXPECT_EQ(mesh.tets.row(0), (Eigen::RowVector4i(0, 1, 2, 3)).cast<std::int32_t>());
  EXPECT_EQ(mesh.nodes.row(1), Eigen::RowVector3d(1, 0, 0));
}
