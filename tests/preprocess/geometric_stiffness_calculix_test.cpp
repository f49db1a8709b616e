// The stressed shape behind the geometric stiffness (issue 29) against CalculiX: the static state that K_σ is built
// from, for a part spinning on a hub. fbprep finds it from the body's unit cases on the free part, with inertia relief
// and its rbe2 patch held rigid (static_correction.hpp: relieved_static_responses); the runtime weighs the cases by
// the spin (centrifugal, λ = ω̄ ω̄ᵀ) and by the reaction at the hub (the interface's unit force and moment). ccx solves
// the clamped part under its centrifugal load (*DLOAD CENTRIF) on the same mesh. The two must differ only by a rigid
// motion: the relieved part floats, the clamped one does not.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/box_mesh.hpp"
#include "flexbody/preprocess/eigensolver.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/geometric_stiffness.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"
#include "flexbody/preprocess/static_correction.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"
#include "calculix.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <memory>

namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};

// The rigid motion t + θ × (x − c) that fits the displacements `u` of `nodes` best (least squares).
Eigen::Matrix<double, 6, 1> rigid_fit(const fp::RowMatrixX3d& x, const Eigen::VectorXd& u, const Eigen::VectorXi& nodes,
                                      const Eigen::Vector3d& c) {
  Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
  for (Eigen::Index a = 0; a < nodes.size(); ++a) {
    const Eigen::Vector3d d = x.row(nodes(a)).transpose() - c;
    Eigen::Matrix<double, 3, 6> row;
    row << Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, -d.z(), d.y()), Eigen::Vector3d(d.z(), 0, -d.x()),
        Eigen::Vector3d(-d.y(), d.x(), 0);
    normal += row.transpose() * row;
    rhs += row.transpose() * u.segment<3>(3 * nodes(a));
  }
  return normal.ldlt().solve(rhs);
}

}  // namespace

// A steel bar 0.4 x 0.03 x 0.02 m (quadratic tetrahedra), its root face an rbe2 patch, spun at 100 rad/s about an axis
// through a point 0.1 m beside the root, inclined 45° to the bar in the x-y plane: the centrifugal load stretches the
// bar and bends it, and the hub's reaction has a force and a moment. Measured: the two fields differ by 1.6e-7 of the
// largest displacement (3.1 mm), ccx's 7 printed digits; asserted 1e-6. Without the reaction they differ by 100 %.
TEST(GeometricStiffnessCalculiX, TheSpunPartsStressedShapeIsCalculiXs) {
  FLEXBODY_REQUIRE_CCX_OR_SKIP();
  constexpr double kLength = 0.4, kWidth = 0.03, kHeight = 0.02, kSpin = 100.0;  // [m], [rad/s]
  fp::TetMesh linear = fp::box_mesh(kLength, kWidth, kHeight, 16, 2, 2);
  linear.nodes.rowwise() -= Eigen::RowVector3d(kLength / 2, kWidth / 2, kHeight / 2);  // body frame: the centre of mass
  const fp::Tet10Mesh mesh = fp::quadratic_mesh(linear);
  const fp::Tet10Matrices matrices = fp::assemble_tet10(mesh, kSteel);
  const fp::RowMatrixX3d& x = mesh.nodes;
  const Eigen::Index n = x.rows();

  fp::LoadPoint root;  // the root face, as fbprep's interface selection makes it (area weights do not matter here)
  root.name = "root";
  std::vector<int> face;
  for (Eigen::Index i = 0; i < n; ++i)
    if (std::abs(x(i, 0) + kLength / 2) < 1e-12) face.push_back(static_cast<int>(i));
  root.nodes = Eigen::Map<const Eigen::VectorXi>(face.data(), static_cast<Eigen::Index>(face.size()));
  root.weights = Eigen::VectorXd::Constant(root.nodes.size(), 1.0 / static_cast<double>(root.nodes.size()));
  for (Eigen::Index a = 0; a < root.nodes.size(); ++a) root.reference_point += root.weights(a) * x.row(root.nodes(a)).transpose();

  // The spin: ω = Ω e about the axis through p.
  const Eigen::Vector3d e = Eigen::Vector3d(1.0, 1.0, 0.0).normalized();
  const Eigen::Vector3d p = root.reference_point + Eigen::Vector3d(0.0, 0.1, 0.0);
  const Eigen::Vector3d omega = kSpin * e;
  // The weights of the six centrifugal cases (geometric_stiffness.hpp): ω_x², ω_y², ω_z², ω_x ω_y, ω_x ω_z, ω_y ω_z, as
  // runtime::prestress_weights forms them (this test does not link the runtime).
  Eigen::Matrix<double, 6, 1> spin_weights;
  spin_weights << omega.x() * omega.x(), omega.y() * omega.y(), omega.z() * omega.z(), omega.x() * omega.y(),
      omega.x() * omega.z(), omega.y() * omega.z();
  // The hub's reaction on the part: minus the resultant of the centrifugal nodal forces about the axis, and minus their
  // moment about the root's reference point (the interface's unit moment is about it).
  Eigen::VectorXd field(3 * n), about_axis(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d r = x.row(i).transpose() - p;
    field.segment<3>(3 * i) = kSpin * kSpin * (r - e * e.dot(r));
  }
  fp::apply_vector_mass(matrices.scalar_mass, field, about_axis);
  Eigen::Vector3d force = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < n; ++i) {
    force -= about_axis.segment<3>(3 * i);
    moment -= (x.row(i).transpose() - root.reference_point).cross(about_axis.segment<3>(3 * i));
  }
  Eigen::Matrix<double, 6, 1> reaction;
  reaction << force, moment;

  // fbprep's cases and their relieved responses with the root held rigid, weighted as the runtime weighs them.
  Eigen::MatrixXd loads(3 * n, 12);
  loads << fp::centrifugal_unit_loads(x, matrices.scalar_mass), fp::unit_load_vectors(x, {root});
  const Eigen::MatrixXd rigid = fp::rigid_body_modes(x, matrices.scalar_mass);
  const std::unique_ptr<fp::ShiftSolve> solve =
      fp::make_shift_solve(fp::EigensolverBackend::arpack, matrices.stiffness, matrices.scalar_mass, rigid);
  solve->set_shift(fp::automatic_shift(x, kSteel));
  fp::StaticCorrectionStats stats;
  const fp::RigidPatches held{&x, {fp::RigidInterface{root.nodes, root.reference_point}}};
  const Eigen::MatrixXd responses = fp::relieved_static_responses(*solve, matrices.stiffness, matrices.scalar_mass, rigid,
                                                                  loads, stats, {}, "spun bar", held);
  Eigen::VectorXd ours = responses.leftCols(6) * spin_weights + responses.rightCols(6) * reaction;

  // ccx: the root clamped, the centrifugal load, a linear static step.
  std::string deck = "*BOUNDARY\n";
  for (Eigen::Index a = 0; a < root.nodes.size(); ++a) deck += fmt::format("{}, 1, 3\n", root.nodes(a) + 1);
  deck += fmt::format("*STEP\n*STATIC\n*DLOAD\nEALL, CENTRIF, {:.14g}, {:.14g}, {:.14g}, {:.14g}, {:.14g}, {:.14g}, "
                      "{:.14g}\n*NODE PRINT, NSET=NALL\nU\n*END STEP\n",
                      kSpin * kSpin, p.x(), p.y(), p.z(), e.x(), e.y(), e.z());
  const auto dir = flexbody::test::scratch_dir();
  flexbody::test::write_inp(dir / "spun.inp", x, mesh.tets, kSteel.youngs_modulus, kSteel.poisson_ratio, kSteel.density,
                            deck);
  ASSERT_TRUE(flexbody::test::run_ccx(dir, "spun"));
  const Eigen::VectorXd ccx = flexbody::test::read_displacements(dir / "spun.dat", n);
  ASSERT_TRUE(ccx.allFinite()) << "ccx printed no displacement for some node";

  // Ours moved rigidly so that its root stays where ccx clamps it.
  const Eigen::Matrix<double, 6, 1> motion = rigid_fit(x, ours, root.nodes, root.reference_point);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d d = x.row(i).transpose() - root.reference_point;
    ours.segment<3>(3 * i) -= motion.head<3>() + motion.tail<3>().cross(d);
  }
  const double largest = ccx.cwiseAbs().maxCoeff(), difference = (ours - ccx).cwiseAbs().maxCoeff();
  std::printf("largest displacement %.3e m, off ccx by %.2e of it; root's rigid motion removed %.2e m\n", largest,
              difference / largest, motion.head<3>().norm());
  EXPECT_GT(largest, 1e-3);  // a load that shows: stretched and bent by millimetres
  EXPECT_LT(difference, 1e-6 * largest);
  // Without the hub's reaction (the free part's inertia relief alone), the root is loaded by nothing and the bar is
  // stressed as if it floated: far from ccx's.
  Eigen::VectorXd free = responses.leftCols(6) * spin_weights;
  const Eigen::Matrix<double, 6, 1> free_motion = rigid_fit(x, free, root.nodes, root.reference_point);
  for (Eigen::Index i = 0; i < n; ++i)
    free.segment<3>(3 * i) -= free_motion.head<3>() + free_motion.tail<3>().cross(x.row(i).transpose() - root.reference_point);
  EXPECT_GT((free - ccx).cwiseAbs().maxCoeff(), 0.3 * largest);
}
