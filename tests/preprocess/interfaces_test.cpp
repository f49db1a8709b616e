// Interfaces: the selectors (plane, cylinder, box) on surface nodes, the area weights, the marker's
// row of Y and its rotation matrix, and every refusal (one message naming the interface).
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/interfaces.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "flexbody/preprocess/mesh_topology.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <numbers>

namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};

// A part in its input frame and body frame.
struct Part {
  fp::RowMatrixX3d body_nodes;
  Eigen::Vector3d com;
  fp::RowMatrixX3i surface;
};

Part make_part(const fp::TetMesh& mesh) {
  const auto model = flexbody::test::assemble(mesh, kSteel);
  Part part;
  part.com = fp::mass_properties(model.scalar_mass, mesh.nodes).center_of_mass_input;
  part.body_nodes = mesh.nodes.rowwise() - part.com.transpose();
  part.surface = fp::boundary_triangles(mesh);
  return part;
}

const Part& bar() {  // 0.3 x 0.05 x 0.03 m, 6 x 2 x 2 cells
  static const Part part = make_part(flexbody::test::box_mesh(0.3, 0.05, 0.03, 6, 2, 2));
  return part;
}

const Part& bracket() {  // meshes/bracket.step at 3 mm
  static const Part part = [] {
    fp::GmshImportOptions options;
    options.mesh_size = 3.0;
    options.order = 1;  // make_part assembles linear tetrahedra
    return make_part(fp::import_tet_mesh(std::filesystem::path(FLEXBODY_SOURCE_DIR) / "meshes" / "bracket.step",
                                         options).mesh);
  }();
  return part;
}

fp::InterfaceRequest request(std::string name, fp::Selector selector) {
  return {std::move(name), std::move(selector), "rbe3"};
}

std::vector<flexbody::format::Interface> build(const Part& part, const std::vector<fp::InterfaceRequest>& requests,
                                               const Eigen::MatrixXd& fields) {
  return fp::build_interfaces(requests, part.body_nodes, part.com, part.surface, fields);
}

void expect_refused(const Part& part, const std::vector<fp::InterfaceRequest>& requests, const std::string& message) {
  try {
    (void)build(part, requests, Eigen::MatrixXd::Zero(part.body_nodes.rows(), 1));
    ADD_FAILURE() << "accepted; expected: " << message;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(Interfaces, PlaneTakesTheEndFaceWithAreaWeights) {
  const Part& part = bar();
  const auto markers = build(part, {request("root", fp::PlaneSelector{{0, 0, 0}, {-2, 0, 0}, 0.0})},
                             Eigen::MatrixXd::Zero(part.body_nodes.rows(), 2));
  ASSERT_EQ(markers.size(), 1u);
  const auto& root = markers[0];
  EXPECT_EQ(root.nodes.size(), 9);  // the 3 x 3 grid nodes of the end face
  for (Eigen::Index j = 0; j < root.nodes.size(); ++j)
    EXPECT_NEAR(part.body_nodes(root.nodes(j), 0) + part.com.x(), 0.0, 1e-15);
  EXPECT_NEAR(root.weights.sum(), 1.0, 1e-15);
  // Area weights put the reference point at the face's centroid exactly (a third of each triangle's
  // area on each of its corners reproduces the area centroid).
  const Eigen::Vector3d centroid_input(0.0, 0.025, 0.015);
  EXPECT_LT((root.reference_point + part.com - centroid_input).norm(), 1e-15);
  EXPECT_EQ(root.y_row.size(), 4 + 2);
  EXPECT_EQ(root.rotation.rows(), 3);
  EXPECT_EQ(root.rotation.cols(), 6);
}

TEST(Interfaces, CylinderTakesABoreOfTheBracket) {
  // Bore 1: axis through (45, 20) mm along z, radius 5 mm, through the 8 mm base plate.
  const Part& part = bracket();
  const auto markers = build(part, {request("bore", fp::CylinderSelector{{0.045, 0.020, 0.0}, {0, 0, 1}, 0.005, 0.0})},
                             Eigen::MatrixXd::Zero(part.body_nodes.rows(), 1));
  const auto& bore = markers[0];
  EXPECT_GT(bore.nodes.size(), 20);
  for (Eigen::Index j = 0; j < bore.nodes.size(); ++j) {
    const Eigen::Vector3d x = part.body_nodes.row(bore.nodes(j)).transpose() + part.com;
    EXPECT_NEAR(std::hypot(x.x() - 0.045, x.y() - 0.020), 0.005, 1e-9);  // nodes lie on the CAD surface
  }
  // The faceted bore is symmetric enough that its area centroid is on the axis, mid-plate.
  const Eigen::Vector3d centre = bore.reference_point + part.com;
  EXPECT_NEAR(centre.x(), 0.045, 1e-5);
  EXPECT_NEAR(centre.y(), 0.020, 1e-5);
  EXPECT_NEAR(centre.z(), 0.004, 1e-5);
}

TEST(Interfaces, MarkerPositionIsTheWeightedAverageForAnyCoordinates) {
  const Part& part = bar();
  const Eigen::Index n_n = part.body_nodes.rows(), n_f = 3;
  const Eigen::MatrixXd fields = Eigen::MatrixXd::Random(n_n, n_f);
  const auto markers = build(part, {request("tip", fp::BoxSelector{{0.29, -1, -1}, {1, 1, 1}})}, fields);
  const auto& tip = markers[0];
  // r = (Y ⊗ I3) q for every node and for the marker: the marker is the weighted node average.
  const Eigen::VectorXd q = Eigen::VectorXd::Random(3 * (4 + n_f));
  auto position = [&](const Eigen::VectorXd& y_row) {
    Eigen::Vector3d r = Eigen::Vector3d::Zero();
    for (Eigen::Index j = 0; j < y_row.size(); ++j) r += y_row(j) * q.segment<3>(3 * j);
    return r;
  };
  Eigen::Vector3d average = Eigen::Vector3d::Zero();
  for (Eigen::Index j = 0; j < tip.nodes.size(); ++j) {
    Eigen::VectorXd y(4 + n_f);
    y << 1.0, part.body_nodes.row(tip.nodes(j)).transpose(), fields.row(tip.nodes(j)).transpose();
    average += tip.weights(j) * position(y);
  }
  EXPECT_LT((position(tip.y_row) - average).norm(), 1e-13 * average.norm());
}

TEST(Interfaces, RotationRecoversARigidRotationOfTheNodes) {
  // Fields equal to the body coordinates x, y, z: ξ̄ = columns of skew(θ) displaces every node by
  // θ × X̄, a rigid rotation, which R must return exactly, for every selector shape.
  const Part& part = bracket();
  const Eigen::MatrixXd fields = part.body_nodes;
  const Eigen::Vector3d theta(0.3, -0.7, 0.2);
  Eigen::Matrix3d s;
  s << 0, -theta.z(), theta.y(), theta.z(), 0, -theta.x(), -theta.y(), theta.x(), 0;
  Eigen::VectorXd xi(9);
  for (int f = 0; f < 3; ++f) xi.segment<3>(3 * f) = s.col(f);  // u = Σ_f X̄_f ξ̄_f = S X̄
  const auto markers = build(part,
                             {request("bore", fp::CylinderSelector{{0.075, 0.020, 0.0}, {0, 0, 1}, 0.005, 0.0}),
                              request("side", fp::PlaneSelector{{0, 0, 0}, {0, 1, 0}, 0.0}),
                              request("upright", fp::CylinderSelector{{0, 0.020, 0.042}, {1, 0, 0}, 0.006, 0.0})},
                             fields);
  for (const auto& marker : markers) {
    SCOPED_TRACE(marker.name);
    EXPECT_LT((marker.rotation * xi - theta).norm(), 1e-12 * theta.norm());
  }
}

TEST(Interfaces, RefusalsNameTheInterface) {
  const Part& part = bar();
  expect_refused(part, {request("far", fp::PlaneSelector{{5, 0, 0}, {1, 0, 0}, 0.0})},
                 "interface 'far': the selector takes no node of the part");
  expect_refused(part, {request("edge", fp::BoxSelector{{-1, -1, -1}, {1e-9, 1e-9, 1}})},
                 "interface 'edge': the selector takes 3 nodes but no whole surface triangle");
  expect_refused(part,
                 {request("root", fp::PlaneSelector{{0, 0, 0}, {1, 0, 0}, 0.0}),
                  request("corner", fp::BoxSelector{{-1, -1, -1}, {0.06, 0.03, 1}})},
                 "interface 'root' and interface 'corner' share node");
  expect_refused(part, {request("a", fp::PlaneSelector{}), request("a", fp::BoxSelector{{0.2, -1, -1}, {1, 1, 1}})},
                 "interface 'a' is defined twice");
  expect_refused(part, {{"glued", fp::PlaneSelector{}, "tied"}}, "interface 'glued': coupling 'tied' is unknown");
  expect_refused(part, {request("flat", fp::PlaneSelector{{0, 0, 0}, {0, 0, 0}, 0.0})},
                 "interface 'flat': the plane normal must be a non-zero vector");
  expect_refused(part, {request("thin", fp::CylinderSelector{{0, 0, 0}, {1, 0, 0}, -1.0, 0.0})},
                 "interface 'thin': the cylinder radius must be positive");
}
