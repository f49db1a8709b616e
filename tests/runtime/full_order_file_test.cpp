// The full-order body of a body file (issue 14, fbsim's `modes: full`): K̄ and M_s assembled again in the runtime from
// the file's mesh and material must be fbprep's, and an rbe2 interface's affine node set must make the body the
// improved GCMS of that field space, which is the space the Craig-Bampton fields of the file span at all modes.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/interfaces.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"
#include "flexbody/runtime/full_order.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace fr = flexbody::runtime;
namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};

// A body file's data for a box mesh: nodes in the body frame, the mesh's boundary, the material; no modes.
struct BoxBody {
  flexbody::test::AssembledMesh fe;
  flexbody::format::BodyData data;
  std::vector<int> root;  // the nodes of the face x = 0
};

BoxBody box_body(double lx, double ly, double lz, int nx, int ny, int nz) {
  BoxBody b;
  b.fe = flexbody::test::assemble(flexbody::test::box_mesh(lx, ly, lz, nx, ny, nz), kSteel);
  b.data.mass = fp::mass_properties(b.fe.scalar_mass, b.fe.mesh.nodes);
  b.data.material = {"steel", kSteel.youngs_modulus, kSteel.poisson_ratio, kSteel.density};
  b.data.mesh.nodes = b.fe.mesh.nodes.rowwise() - b.data.mass.center_of_mass_input.transpose();
  b.data.mesh.tets = b.fe.mesh.tets;
  for (Eigen::Index i = 0; i < b.fe.mesh.nodes.rows(); ++i)
    if (b.fe.mesh.nodes(i, 0) == 0.0) b.root.push_back(static_cast<int>(i));
  return b;
}

double relative_difference(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
  return (a - b).norm() / b.norm();
}

// The interface of the nodes `set` with equal weights.
fp::SurfacePatch patch_of(const std::vector<int>& set) {
  fp::SurfacePatch patch;
  patch.nodes = Eigen::Map<const Eigen::VectorXi>(set.data(), static_cast<Eigen::Index>(set.size()));
  patch.weights = Eigen::VectorXd::Constant(patch.nodes.size(), 1.0 / static_cast<double>(set.size()));
  return patch;
}

}  // namespace

TEST(FullOrderFromFile, AssemblesTheMatricesFbprepAssembled) {
  // The same element integrals summed in another order (triplets against fbprep's node columns): equal to round-off.
  const BoxBody b = box_body(0.3, 0.05, 0.04, 6, 2, 2);
  const fr::BodyModel model = fr::full_order_model(b.data, "box");
  ASSERT_TRUE(model.sparse);
  EXPECT_EQ(model.sparse->fields.rows(), 0);  // no rbe2 interface: Ῡ' = I
  EXPECT_LT(relative_difference(model.sparse->stiffness, fp::full_from_upper(b.fe.stiffness)), 1e-14);
  EXPECT_LT(relative_difference(model.sparse->mass, fp::full_from_upper(b.fe.scalar_mass)), 1e-14);
  EXPECT_NEAR(model.mass, kSteel.density * 0.3 * 0.05 * 0.04, 1e-12 * model.mass);
}

// Quadratic tetrahedra (issue 15): the runtime assembles the body file's 10-node elements with fbprep's element
// integrals (K̄ by the 4-point rule, the exact consistent mass), so its K̄ and M_s are preprocess::assemble_tet10's to
// round-off; the mass is the box's. A folded element is refused by name.
TEST(FullOrderFromFile, AssemblesQuadraticTetrahedraAsFbprepDoes) {
  const fp::Tet10Mesh mesh = fp::quadratic_mesh(flexbody::test::box_mesh(0.3, 0.05, 0.04, 6, 2, 2));
  const fp::Tet10Matrices fe = fp::assemble_tet10(mesh, kSteel);
  flexbody::format::BodyData data;
  data.mass = fp::mass_properties(fe.scalar_mass, mesh.nodes);
  data.material = {"steel", kSteel.youngs_modulus, kSteel.poisson_ratio, kSteel.density};
  data.mesh.nodes = mesh.nodes.rowwise() - data.mass.center_of_mass_input.transpose();
  data.mesh.tets = mesh.tets;
  data.mesh.element_order = 2;
  const fr::BodyModel model = fr::full_order_model(data, "box");
  ASSERT_TRUE(model.sparse);
  EXPECT_EQ(model.sparse->stiffness.rows(), mesh.dof_count());
  EXPECT_LT(relative_difference(model.sparse->stiffness, fp::full_from_upper(fe.stiffness)), 1e-14);
  EXPECT_LT(relative_difference(model.sparse->mass, fp::full_from_upper(fe.scalar_mass)), 1e-14);
  EXPECT_NEAR(model.mass, kSteel.density * 0.3 * 0.05 * 0.04, 1e-12 * model.mass);

  flexbody::format::BodyData folded = data;
  folded.mesh.nodes.row(folded.mesh.tets(5, 4)) = folded.mesh.nodes.row(folded.mesh.tets(5, 2));
  try {
    static_cast<void>(fr::full_order_model(folded, "box.fbh5"));
    ADD_FAILURE() << "a folded element was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("box.fbh5: quadratic tetrahedron"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("is inverted or folded"), std::string::npos) << e.what();
  }
}

TEST(FullOrderFromFile, RefusesBadMeshesAndOverlappingRbe2Sets) {
  BoxBody b = box_body(0.3, 0.05, 0.04, 6, 2, 2);
  flexbody::format::BodyData inverted = b.data;
  std::swap(inverted.mesh.tets(7, 1), inverted.mesh.tets(7, 2));
  try {
    static_cast<void>(fr::full_order_model(inverted, "box.fbh5"));
    ADD_FAILURE() << "an inverted element was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("box.fbh5: tetrahedron 7 is inverted or flat"), std::string::npos) << e.what();
  }
  flexbody::format::BodyData orphan = b.data;  // a node that no tetrahedron holds: no mass, no stiffness
  orphan.mesh.nodes.conservativeResize(orphan.mesh.nodes.rows() + 1, 3);
  orphan.mesh.nodes.bottomRows<1>() << 1.0, 1.0, 1.0;
  try {
    static_cast<void>(fr::full_order_model(orphan, "box.fbh5"));
    ADD_FAILURE() << "a node outside every element was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("box.fbh5: node " + std::to_string(b.data.mesh.nodes.rows()) +
                                         " belongs to no tetrahedron"), std::string::npos) << e.what();
  }
  flexbody::format::BodyData beyond = b.data;
  beyond.mesh.tets(3, 2) = static_cast<std::int32_t>(beyond.mesh.nodes.rows());
  EXPECT_THROW(static_cast<void>(fr::full_order_model(beyond, "box.fbh5")), std::invalid_argument);
  const Eigen::MatrixXd none(b.data.mesh.nodes.rows(), 0);
  for (const char* name : {"a", "b"})
    b.data.interfaces.push_back(fp::interface_marker(name, "rbe2", patch_of(b.root), b.data.mesh.nodes, none));
  try {
    static_cast<void>(fr::full_order_model(b.data, "box.fbh5"));
    ADD_FAILURE() << "overlapping rbe2 sets were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rbe2 interfaces 'a' and 'b' share node"), std::string::npos) << e.what();
  }
}

TEST(FullOrderFromFile, CraigBamptonFieldsAreAffineOnTheirRbe2Set) {
  // The premise of the affine node sets: every field of a Craig-Bampton basis with an rbe2 interface is, over that
  // interface's nodes, a combination of 1, y and z (the face x = 0 is flat), to the round-off of the eigensolver's
  // constraint (1e-10 of the field's largest value; measured at most 7e-16).
  const BoxBody b = box_body(0.5, 0.05, 0.05, 10, 2, 2);
  fp::RigidInterface clamp;
  clamp.nodes = patch_of(b.root).nodes;
  clamp.reference_point = Eigen::Vector3d::Zero();
  for (int i : b.root) clamp.reference_point += b.data.mesh.nodes.row(i).transpose() / static_cast<double>(b.root.size());
  fp::CraigBamptonOptions options;
  options.fixed_interface_modes = 6;
  const fp::CraigBamptonModes cb =
      fp::craig_bampton_modes(b.data.mesh.nodes, b.fe.stiffness, b.fe.scalar_mass, kSteel, {clamp}, options);
  const Eigen::MatrixXd upsilon = fp::upsilon_from_modes(cb.vectors);
  Eigen::MatrixXd affine(static_cast<Eigen::Index>(b.root.size()), 3);
  for (std::size_t j = 0; j < b.root.size(); ++j)
    affine.row(static_cast<Eigen::Index>(j)) << 1.0, b.data.mesh.nodes(b.root[j], 1), b.data.mesh.nodes(b.root[j], 2);
  ASSERT_GT(upsilon.cols(), 12);
  for (Eigen::Index f = 0; f < upsilon.cols(); ++f) {
    Eigen::VectorXd on_root(static_cast<Eigen::Index>(b.root.size()));
    for (std::size_t j = 0; j < b.root.size(); ++j) on_root(static_cast<Eigen::Index>(j)) = upsilon(b.root[j], f);
    const Eigen::VectorXd fit = affine * affine.colPivHouseholderQr().solve(on_root);
    EXPECT_LT((on_root - fit).cwiseAbs().maxCoeff(), 1e-10 * upsilon.col(f).cwiseAbs().maxCoeff()) << f;
  }
}

TEST(FullOrderFromFile, AnRbe2SetMovesAsTheImprovedGcmsOfItsAffineFields) {
  // A 0.2 x 0.05 x 0.05 m steel block (4 x 1 x 1 cells, 20 nodes) whose face x = 0 is an rbe2 interface, pinned there
  // by a revolute joint at the interface marker and released horizontal. The runtime's full-order body (sparse, its
  // fields T built by full_order_model) against a dense improved-GCMS body built here from the same field space by
  // other hands: a unit field for each other node and 1, y, z over the face (its independent affine functions), with
  // fbprep's marker of that interface. Two bases of one space, two code paths (sparse core, dense G and K̂), one model:
  // the tip paths must agree to the Newton tolerance. Light stiffness damping (β = 1e-6 s) in both lets the release's
  // ~100 kHz transient decay.
  BoxBody b = box_body(0.2, 0.05, 0.05, 4, 1, 1);
  const Eigen::MatrixXd none(b.data.mesh.nodes.rows(), 0);
  b.data.interfaces.push_back(fp::interface_marker("root", "rbe2", patch_of(b.root), b.data.mesh.nodes, none));
  const double beta = 1e-6;
  const fr::BodyModel full = fr::damp_full_order(fr::full_order_model(b.data, "block"), beta);
  ASSERT_EQ(full.field_count(), 20 - 4 + 3);  // the flat face has three independent affine functions

  const fp::RowMatrixX3d& nodes = b.data.mesh.nodes;
  const Eigen::Index n_n = nodes.rows();
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(n_n, n_n - 4 + 3);
  Eigen::Index column = 0;
  for (Eigen::Index i = 0; i < n_n; ++i)
    if (b.fe.mesh.nodes(i, 0) != 0.0) t(i, column++) = 1.0;
  for (int i : b.root) t.block<1, 3>(i, column) << 1.0, nodes(i, 1), nodes(i, 2);
  const Eigen::MatrixXd m_s = Eigen::MatrixXd(fp::full_from_upper(b.fe.scalar_mass));
  const Eigen::MatrixXd k = Eigen::MatrixXd(fp::full_from_upper(b.fe.stiffness));
  Eigen::MatrixXd y(n_n, 4 + t.cols());
  y << Eigen::VectorXd::Ones(n_n), nodes, t;
  Eigen::MatrixXd expanded = Eigen::MatrixXd::Zero(3 * n_n, 3 * t.cols());  // T ⊗ I3
  for (Eigen::Index i = 0; i < n_n; ++i)
    for (Eigen::Index f = 0; f < t.cols(); ++f) expanded.block<3, 3>(3 * i, 3 * f).diagonal().setConstant(t(i, f));
  fr::BodyModel dense;
  dense.source = "dense";
  dense.mass = b.data.mass.mass;
  dense.mass_matrix = y.transpose() * m_s * y;
  dense.stiffness = expanded.transpose() * k * expanded;
  dense.damping = beta * dense.stiffness;
  dense.tisserand = dense.mass_matrix.block(1, 4, 3, t.cols());
  dense.fields = t;
  dense.nodes = nodes;
  dense.mode_coefficients.resize(t.cols(), 0);
  dense.interfaces.push_back(fp::interface_marker("root", "rbe2", patch_of(b.root), nodes, t));
  ASSERT_TRUE(dense.needs_translational_tisserand());

  Eigen::Index far = 0;
  b.fe.mesh.nodes.rowwise().sum().maxCoeff(&far);
  auto path = [&](const fr::BodyModel& body) {  // 0.05 s at h = 1e-4 s
    fr::System system;
    const int id = system.add_body("block", body, fr::BodyState{});
    const fr::Marker root = fr::interface_marker(body, id, "block", "root"), tip = fr::node_marker(body, id, "block", far);
    const Eigen::VectorXd q0 = system.initial_coordinates();
    system.add_joint(fr::make_joint("pin", fr::JointType::revolute, root, fr::ground_marker(fr::marker_position(root, q0)),
                                    Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd()));
    system.set_gravity(Eigen::Vector3d(0, -9.81, 0));
    fr::GeneralizedAlphaOptions options;
    options.step = 1e-4;
    options.tolerance = 1e-10;
    fr::GeneralizedAlpha integrator(system, options);
    std::vector<Eigen::Vector3d> out;
    for (int i = 0; i < 500; ++i) {
      integrator.step();
      out.push_back(fr::marker_position(tip, system.body_coordinates(integrator.coordinates(), id)));
    }
    return out;
  };
  const std::vector<Eigen::Vector3d> by_sparse = path(full), by_dense = path(dense);
  double travel = 0.0, largest = 0.0;
  for (std::size_t s = 0; s < by_sparse.size(); ++s) {
    travel = std::max(travel, (by_dense[s] - by_dense.front()).norm());
    largest = std::max(largest, (by_sparse[s] - by_dense[s]).norm());
  }
  ASSERT_GT(travel, 5e-3);  // the block swings ~1 cm in 0.05 s
  // The Newton tolerance is 1e-10 of the length scales; measured 3.3e-13 m of 1.8e-2 m travel (2e-11).
  EXPECT_LT(largest, 1e-9 * travel) << largest;
}
