// Mesh checks and derived topology: orientation, connectivity, boundary surface, element quality.
#include "flexbody/preprocess/mesh_topology.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"
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

// A quadratic mesh's boundary (issue 15): each 6-node face as 4 triangles, so 4 times the linear boundary's count, the
// same area (2 (ab + bc + ca) for the box), outward (the divergence theorem: ⅓ Σ A n · centroid = V), and every node on
// the box's faces (corners and mid-edge nodes) a triangle corner, no interior node. The quality of straight-sided
// elements: Jacobian ratio 1, the corners' radius ratios, the volume exact.
TEST(MeshTopology, QuadraticBoundaryIsEachFaceSplitInFour) {
  const double a = 0.3, b = 0.2, c = 0.1;
  const fp::TetMesh linear = flexbody::test::box_mesh(a, b, c, 3, 2, 2);
  const fp::Tet10Mesh mesh = fp::quadratic_mesh(linear);
  const fp::RowMatrixX3i triangles = fp::boundary_triangles(mesh);
  ASSERT_EQ(triangles.rows(), 4 * fp::boundary_triangles(linear).rows());
  double area = 0.0, volume = 0.0;
  std::vector<char> used(static_cast<std::size_t>(mesh.node_count()), 0);
  for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
    const Eigen::Vector3d p = mesh.nodes.row(triangles(t, 0)), q = mesh.nodes.row(triangles(t, 1)),
                          r = mesh.nodes.row(triangles(t, 2));
    const Eigen::Vector3d normal_area = 0.5 * (q - p).cross(r - p);
    area += normal_area.norm();
    volume += normal_area.dot((p + q + r) / 3.0) / 3.0;
    for (int k = 0; k < 3; ++k) used[static_cast<std::size_t>(triangles(t, k))] = 1;
  }
  EXPECT_NEAR(area, 2.0 * (a * b + b * c + c * a), 1e-14);
  EXPECT_NEAR(volume, a * b * c, 1e-15);
  for (Eigen::Index i = 0; i < mesh.node_count(); ++i) {
    const Eigen::Vector3d x = mesh.nodes.row(i);
    const bool on_face = x.minCoeff() < 1e-12 || std::abs(x.x() - a) < 1e-12 || std::abs(x.y() - b) < 1e-12 ||
                         std::abs(x.z() - c) < 1e-12;
    EXPECT_EQ(used[static_cast<std::size_t>(i)] != 0, on_face) << "node " << i;
  }
  const fp::MeshQuality quality = fp::mesh_quality(mesh);
  EXPECT_NEAR(quality.min_jacobian_ratio, 1.0, 1e-12);
  EXPECT_EQ(quality.min_radius_ratio, fp::mesh_quality(linear).min_radius_ratio);
  EXPECT_NEAR(quality.volume_m3, a * b * c, 1e-15);
}
