// Issue 27, item 4: redundant constraints. A planar four-bar of revolute joints in 3D repeats three of its rows (the
// translation normal to its plane and the two tilts of its axes); System::remove_redundant_constraints leaves them
// out of the last joint, as Adams does, and the linkage runs. Its reactions are checked against the statics of the
// plane (free-body diagrams of the three links, solved here), and its motion against what the removed rows held.
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/initial_assembly.hpp"
#include "flexbody/runtime/system.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace fr = flexbody::runtime;

namespace {

constexpr double kGravity = 9.81, kWidth = 0.04;

// The pins in the plane z = 0: crank A -> B, coupler B -> C, rocker D -> C (a crank-rocker, not a parallelogram,
// so that no reaction is zero by symmetry).
const Eigen::Vector3d kA(0.0, 0.0, 0.0), kB(0.3, 0.4, 0.0), kC(1.2, 0.6, 0.0), kD(1.0, 0.0, 0.0);
constexpr double kMasses[3] = {2.0, 3.0, 1.5};  // crank, coupler, rocker [kg]

struct Link {
  int body;
  fr::Marker from, to;  // markers at its two pins
};

// A uniform rigid bar from p to q (its x axis), mass m: J = ∫ x xᵀ dm = m diag(L², w², w²) / 12.
Link add_bar(fr::System& system, std::vector<fr::BodyModel>& models, const std::string& name, const Eigen::Vector3d& p,
             const Eigen::Vector3d& q, double m) {
  const double length = (q - p).norm();
  models.push_back(fr::rigid_body_model(m, m / 12.0 * Eigen::Vector3d(length * length, kWidth * kWidth, kWidth * kWidth).asDiagonal(),
                                        name));
  fr::BodyState state;
  state.position = 0.5 * (p + q);
  state.orientation = Eigen::AngleAxisd(std::atan2(q.y() - p.y(), q.x() - p.x()), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const int body = system.add_body(name, models.back(), state);
  return {body, fr::point_marker(models.back(), body, name, Eigen::Vector3d(-length / 2, 0, 0)),
          fr::point_marker(models.back(), body, name, Eigen::Vector3d(length / 2, 0, 0))};
}

// The four-bar with gravity along −y; the crank's pin is a driven revolute held at its angle (`held`: a structure)
// or a revolute (the linkage swings). `d_lift` [m] puts D's ground pin off the plane: the loop then does not close.
fr::System four_bar(std::vector<fr::BodyModel>& models, bool held, double d_lift = 0.0) {
  models.reserve(3);  // the markers and the system keep pointers into the models
  fr::System system;
  const Link crank = add_bar(system, models, "crank", kA, kB, kMasses[0]);
  const Link coupler = add_bar(system, models, "coupler", kB, kC, kMasses[1]);
  const Link rocker = add_bar(system, models, "rocker", kD, kC, kMasses[2]);
  const Eigen::VectorXd q = system.initial_coordinates();
  auto coordinates = [&](int body) { return system.body_coordinates(q, body); };
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  system.add_joint(fr::make_joint("A", held ? fr::JointType::driven_revolute : fr::JointType::revolute, crank.from,
                                  fr::ground_marker(kA), z, coordinates(crank.body), Eigen::VectorXd(),
                                  held ? std::function<double(double)>([](double) { return 0.0; }) : nullptr));
  system.add_joint(fr::make_joint("B", fr::JointType::revolute, coupler.from, crank.to, z, coordinates(coupler.body),
                                  coordinates(crank.body)));
  system.add_joint(fr::make_joint("C", fr::JointType::revolute, rocker.to, coupler.to, z, coordinates(rocker.body),
                                  coordinates(coupler.body)));
  system.add_joint(fr::make_joint("D", fr::JointType::revolute, rocker.from, fr::ground_marker(kD + d_lift * z), z,
                                  coordinates(rocker.body), Eigen::VectorXd()));
  system.set_gravity(Eigen::Vector3d(0, -kGravity, 0));
  return system;
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// The statics of the held linkage in its plane: x = [F_A (2), M_A, F_B (2), F_C (2), F_D (2)], F_A and M_A from
// ground on the crank at A, F_B from the coupler on the crank, F_C from the rocker on the coupler, F_D from ground
// on the rocker. Three free-body diagrams, three equations each.
Eigen::VectorXd planar_statics() {
  const Eigen::Vector2d a = kA.head<2>(), b = kB.head<2>(), c = kC.head<2>(), d = kD.head<2>();
  const Eigen::Vector2d w[3] = {{0, -kMasses[0] * kGravity}, {0, -kMasses[1] * kGravity}, {0, -kMasses[2] * kGravity}};
  const Eigen::Vector2d g[3] = {0.5 * (a + b), 0.5 * (b + c), 0.5 * (d + c)};  // the centres of mass
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(9, 9);
  Eigen::VectorXd rhs(9);
  // A force f at point p in equation rows: the force rows, and its moment about o: (p − o) × f.
  auto force = [&](int row, int column, double sign, const Eigen::Vector2d& p, const Eigen::Vector2d& o) {
    s(row, column) += sign, s(row + 1, column + 1) += sign;
    s(row + 2, column) += -sign * (p - o).y(), s(row + 2, column + 1) += sign * (p - o).x();
  };
  force(0, 0, 1.0, a, a);  // crank: F_A, M_A, F_B, weight, moments about A
  s(2, 2) = 1.0;
  force(0, 3, 1.0, b, a);
  rhs.segment<3>(0) << -w[0], -cross(g[0] - a, w[0]);
  force(3, 3, -1.0, b, b);  // coupler: −F_B, F_C, weight, moments about B
  force(3, 5, 1.0, c, b);
  rhs.segment<3>(3) << -w[1], -cross(g[1] - b, w[1]);
  force(6, 5, -1.0, c, d);  // rocker: −F_C, F_D, weight, moments about D
  force(6, 7, 1.0, d, d);
  rhs.segment<3>(6) << -w[2], -cross(g[2] - d, w[2]);
  return s.fullPivLu().solve(rhs);
}

}  // namespace

TEST(RedundantConstraints, AFourBarLeavesOutTheLastJointsOutOfPlaneRows) {
  std::vector<fr::BodyModel> models;
  fr::System system = four_bar(models, true);
  ASSERT_EQ(system.constraint_count(), 3 * 6 + 6 + 3 * 5);  // each body's 6 orthogonality rows, 21 joint rows
  const Eigen::VectorXd q0 = system.initial_coordinates();
  EXPECT_GE(system.first_redundant_constraint(0.0, q0), system.joint_row(3));  // the scan reaches joint D first
  const std::vector<fr::RemovedConstraint> removed = system.remove_redundant_constraints(0.0, q0);
  ASSERT_EQ(removed.size(), 3u);
  for (const fr::RemovedConstraint& c : removed) {
    EXPECT_EQ(c.joint, 3u);
    EXPECT_EQ(c.name, "D");
  }
  // The gap normal to the plane, and the axis's two tilts: rotations about directions in the plane.
  EXPECT_EQ(removed[0].row, 2);
  EXPECT_EQ(removed[0].meaning, "translation along z");
  for (int k = 1; k < 3; ++k) {
    EXPECT_EQ(removed[static_cast<std::size_t>(k)].row, 2 + k);
    EXPECT_EQ(removed[static_cast<std::size_t>(k)].meaning.rfind("rotation about [", 0), 0u) << removed[static_cast<std::size_t>(k)].meaning;
    EXPECT_EQ(removed[static_cast<std::size_t>(k)].meaning.substr(removed[static_cast<std::size_t>(k)].meaning.size() - 6), " 0.00]");
  }
  EXPECT_EQ(system.joints()[3].rows(), 2);
  EXPECT_EQ(system.constraint_count(), 3 * 6 + 6 + 3 * 5 - 3);
  EXPECT_EQ(system.first_redundant_constraint(0.0, q0), -1);
  EXPECT_TRUE(system.remove_redundant_constraints(0.0, q0).empty());  // nothing more to remove
}

TEST(RedundantConstraints, TheHeldFourBarsReactionsAreThoseOfItsPlanarStatics) {
  // Exact statics (consistent multipliers at rest: q̈ = 0), so round-off only: 1e-9 of the weights and of their
  // moments over the 1.2 m span. Out of the plane every component is zero: the loads lie in it.
  std::vector<fr::BodyModel> models;
  fr::System system = four_bar(models, true);
  system.remove_redundant_constraints(0.0, system.initial_coordinates());
  fr::GeneralizedAlphaOptions options;
  options.step = 1e-3;
  fr::GeneralizedAlpha integrator(system, options);
  const Eigen::VectorXd x = planar_statics();
  const double weight = (kMasses[0] + kMasses[1] + kMasses[2]) * kGravity, span = 1.2;
  auto expect_wrench = [&](std::size_t joint, const Eigen::Vector2d& force, double moment_z) {
    SCOPED_TRACE("joint " + system.joints()[joint].name);
    const fr::JointReaction r = system.joint_reaction(joint, integrator.time(), integrator.coordinates(), integrator.multipliers());
    EXPECT_LT((r.force - Eigen::Vector3d(force.x(), force.y(), 0.0)).norm(), 1e-9 * weight);
    EXPECT_LT((r.moment - Eigen::Vector3d(0.0, 0.0, moment_z)).norm(), 1e-9 * weight * span);
  };
  for (int k = 0; k < 2; ++k) {  // at t = 0 and after 20 steps: the structure stays at rest
    expect_wrench(0, x.segment<2>(0), x(2));     // ground on the crank at A, with the holding moment
    expect_wrench(1, -x.segment<2>(3), 0.0);     // the crank on the coupler at B
    expect_wrench(2, -x.segment<2>(5), 0.0);     // the coupler on the rocker at C
    expect_wrench(3, x.segment<2>(7), 0.0);      // ground on the rocker at D
    for (int i = 0; i < 20; ++i) integrator.step();
  }
  EXPECT_GT(std::abs(x(2)), 0.1 * weight * span);  // the crank's holding moment is not trivially small
}

TEST(RedundantConstraints, TheFreeFourBarSwingsInItsPlaneAndConservesEnergy) {
  // Released at rest, 0.5 s at ρ∞ = 1: the linkage stays in its plane and the removed rows stay met (they follow
  // from the others), to round-off; the energy is conserved to the Newton tolerance's effect (1e-6 of each step's
  // predictor-corrector distance, as in the rigid pendulum's test).
  std::vector<fr::BodyModel> models;
  fr::System system = four_bar(models, false);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  const fr::Joint whole = system.joints()[3];  // joint D with all five rows, to check the removed ones
  ASSERT_EQ(system.remove_redundant_constraints(0.0, q0).size(), 3u);
  fr::GeneralizedAlphaOptions options;
  options.step = 1e-3;
  options.rho_infinity = 1.0;
  fr::GeneralizedAlpha integrator(system, options);
  const double e0 = system.energies(integrator.coordinates(), integrator.velocities()).total();
  double largest_turn = 0.0;
  for (int i = 0; i < 500; ++i) {
    integrator.step();
    const Eigen::VectorXd& q = integrator.coordinates();
    for (int b = 0; b < 3; ++b) {
      const Eigen::Index o = system.offset(b);
      EXPECT_LT(std::abs(q(o + 2)), 1e-12) << "body " << b << " left the plane at step " << i;  // τ_z
      EXPECT_LT(std::abs(q(o + 5)) + std::abs(q(o + 8)), 1e-12);                             // A(2,0), A(2,1)
    }
    const fr::JointEvaluation e = fr::evaluate_joint(whole, integrator.time(), system.body_coordinates(q, 2), Eigen::VectorXd());
    EXPECT_LT(e.residual.cwiseAbs().maxCoeff(), 1e-12) << "at step " << i;
    largest_turn = std::max(largest_turn, std::abs(std::atan2(q(4), q(3)) - std::atan2(q0(4), q0(3))));
  }
  EXPECT_GT(largest_turn, 0.3);  // the crank swings by more than 17°: a real motion, not a structure at rest
  const double e1 = system.energies(integrator.coordinates(), integrator.velocities()).total();
  const double scale = (kMasses[0] + kMasses[1] + kMasses[2]) * kGravity * 1.0;  // m g times the linkage's size
  EXPECT_LT(std::abs(e1 - e0), 1e-6 * scale);
}

TEST(RedundantConstraints, ALoopThatDoesNotCloseIsRefusedByTheAssembly) {
  // D's ground pin 2 mm off the plane: the rows that D keeps (x, y) are met, the removed translation along z is not.
  // No move closes it (that row is no longer solved for), so the assembly names the joint instead of starting
  // a run that ignores a misfit of 2 mm: above its tolerance of 1e-3 of the rocker's 0.63 m.
  std::vector<fr::BodyModel> models;
  fr::System system = four_bar(models, false, 2e-3);
  ASSERT_EQ(system.remove_redundant_constraints(0.0, system.initial_coordinates()).size(), 3u);
  fr::InitialAssemblyOptions options;
  options.tolerance = 1e-3;
  try {
    fr::initial_assembly(system, options);
    ADD_FAILURE() << "an inconsistent redundant row was accepted";
  } catch (const fr::InitialAssemblyError& e) {
    EXPECT_EQ(e.joint, 3u);
    EXPECT_EQ(std::string(e.what()).rfind("joint 'D': its redundant row (translation along z) is off by 0.002 m", 0), 0u)
        << e.what();
  }
  // Within the tolerance it is accepted, and the removed row's gap is what remove_redundant_constraints reported.
  std::vector<fr::BodyModel> models_small;
  fr::System slightly = four_bar(models_small, false, 1e-5);
  const std::vector<fr::RemovedConstraint> removed = slightly.remove_redundant_constraints(0.0, slightly.initial_coordinates());
  ASSERT_EQ(removed.size(), 3u);
  EXPECT_NEAR(removed[0].gap, 1e-5, 1e-15);
  EXPECT_NO_THROW(fr::initial_assembly(slightly, options));
}

TEST(RedundantConstraints, AJointWithEveryRowRemovedRunsOnTheDenseNewtonMatrix) {
  // A spherical joint at a revolute joint's pivot repeats all three of its rows: it keeps none. The dense reference
  // matrix (with the joints' curvature) and the constant core then agree on the motion of the bar.
  std::vector<fr::BodyModel> models;
  models.reserve(1);
  std::vector<Eigen::VectorXd> ends;
  for (const fr::NewtonMatrix matrix : {fr::NewtonMatrix::constant_core, fr::NewtonMatrix::dense}) {
    fr::System system;
    models.clear();
    const Link bar = add_bar(system, models, "bar", kA, kB, kMasses[0]);
    const Eigen::VectorXd q = system.initial_coordinates();
    system.add_joint(fr::make_joint("pin", fr::JointType::revolute, bar.from, fr::ground_marker(kA), Eigen::Vector3d::UnitZ(),
                                    system.body_coordinates(q, 0), Eigen::VectorXd()));
    system.add_joint(fr::make_joint("ball", fr::JointType::spherical, bar.from, fr::ground_marker(kA), Eigen::Vector3d::UnitZ(),
                                    system.body_coordinates(q, 0), Eigen::VectorXd()));
    system.set_gravity(Eigen::Vector3d(0, -kGravity, 0));
    ASSERT_EQ(system.remove_redundant_constraints(0.0, q).size(), 3u);
    ASSERT_EQ(system.joints()[1].rows(), 0);
    EXPECT_EQ(system.constraint_hessian(0.0, q, Eigen::VectorXd::Ones(system.constraint_count())).rows(), q.size());
    fr::GeneralizedAlphaOptions options;
    options.newton_matrix = matrix;
    fr::GeneralizedAlpha integrator(system, options);
    for (int i = 0; i < 100; ++i) integrator.step();
    const fr::JointReaction r = system.joint_reaction(1, integrator.time(), integrator.coordinates(), integrator.multipliers());
    EXPECT_EQ(r.force.norm(), 0.0);  // it carries nothing: the pin does
    ends.push_back(integrator.coordinates());
  }
  // The same Newton solution, to the iteration's tolerance (1e-6 of each step's predictor-corrector distance).
  EXPECT_LT((ends[0] - ends[1]).norm(), 1e-8);
}

TEST(RedundantConstraints, ASecondCallMapsRowsPastTheOnesRemovedBefore) {
  // A fixed joint at a revolute joint's pivot, whose type rows 1 and 3 were removed by an earlier call: of its
  // kept rows 0, 2, 4 and 5, the first three repeat the revolute's (x, z, the tilt about y), the last (the rotation
  // about the axis) does not. The dependent rows of the compacted joint map to type rows 0, 2 and 4.
  std::vector<fr::BodyModel> models;
  models.reserve(1);
  fr::System system;
  const Link bar = add_bar(system, models, "bar", kA, kB, kMasses[0]);
  const Eigen::VectorXd q = system.initial_coordinates();
  system.add_joint(fr::make_joint("pin", fr::JointType::revolute, bar.from, fr::ground_marker(kA), Eigen::Vector3d::UnitZ(),
                                  system.body_coordinates(q, 0), Eigen::VectorXd()));
  fr::Joint clamp = fr::make_joint("clamp", fr::JointType::fixed, bar.from, fr::ground_marker(kA), Eigen::Vector3d::UnitZ(),
                                   system.body_coordinates(q, 0), Eigen::VectorXd());
  clamp.removed = 0b01010;
  system.add_joint(clamp);
  const std::vector<fr::RemovedConstraint> removed = system.remove_redundant_constraints(0.0, q);
  ASSERT_EQ(removed.size(), 3u);
  EXPECT_EQ(removed[0].row, 0);
  EXPECT_EQ(removed[1].row, 2);
  EXPECT_EQ(removed[2].row, 4);
  EXPECT_EQ(system.joints()[1].removed, 0b11111u);
  EXPECT_EQ(system.joints()[1].rows(), 1);
  EXPECT_EQ(system.first_redundant_constraint(0.0, q), -1);
}

// A drive that repeats what the joints before it hold would be dropped with its row: refused, naming the joint. A bar
// welded to ground (fixed joint) and then driven about z at the same pin: the drive's five revolute rows give way
// as redundant, its angle row is refused.
TEST(RedundantConstraints, ARedundantDriveIsRefusedNotDropped) {
  std::vector<fr::BodyModel> models;
  models.reserve(1);
  fr::System system;
  const Link bar = add_bar(system, models, "bar", kA, kB, kMasses[0]);
  const Eigen::VectorXd q = system.initial_coordinates();
  const Eigen::VectorXd q_bar = system.body_coordinates(q, bar.body);
  system.add_joint(fr::make_joint("weld", fr::JointType::fixed, bar.from, fr::ground_marker(kA), Eigen::Vector3d::UnitZ(),
                                  q_bar, Eigen::VectorXd()));
  system.add_joint(fr::make_joint("drive", fr::JointType::driven_revolute, bar.from, fr::ground_marker(kA),
                                  Eigen::Vector3d::UnitZ(), q_bar, Eigen::VectorXd(), [](double t) { return t; },
                                  [](double) { return 1.0; }));
  try {
    (void)system.remove_redundant_constraints(0.0, q);
    FAIL() << "a redundant drive was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'drive': its driven angle is redundant"), std::string::npos) << e.what();
  }
}
