// The scene builder (issue 31): markers named by body and point, joints by type and markers, give the same System as
// the lower-level make_joint with coordinates and markers built by hand; a driven joint's ramp is smooth and exact.
#include "flexbody/runtime/scene_builder.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

namespace fr = flexbody::runtime;

namespace {

// A 0.4 x 0.04 x 0.02 m steel bar (rigid), its centre of mass at `com` in its input frame.
fr::BodyModel bar() {
  const double m = 7850.0 * 0.4 * 0.04 * 0.02;
  return fr::rigid_body_model(m, m / 12.0 * Eigen::Vector3d(0.4 * 0.4, 0.04 * 0.04, 0.02 * 0.02).asDiagonal().toDenseMatrix(), "bar");
}

}  // namespace

TEST(SceneBuilder, BuildsWhatMakeJointBuilds) {
  const Eigen::Vector3d com(0.2, 0.0, 0.0);  // the bar drawn from x = 0 to 0.4 in its input frame
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  // By the builder: the bar's input frame at (1, 2, 0), turned 0.3 rad about z; pinned at its input-frame origin to
  // ground, a second bar hung from its far end.
  fr::System built;
  fr::SceneBuilder scene(built);
  fr::Placement placement;
  placement.position = Eigen::Vector3d(1.0, 2.0, 0.0);
  placement.rotation = turn;
  scene.add_body("a", bar(), placement, com);
  fr::Placement second;
  second.position = placement.position + turn * Eigen::Vector3d(0.4, 0.0, 0.0);
  second.rotation = turn;
  scene.add_body("b", bar(), second, com);
  const fr::Marker origin = scene.point("a", Eigen::Vector3d::Zero());
  // The input frame's origin is where the placement put it.
  EXPECT_LT((fr::marker_position(origin, built.initial_body_coordinates(0)) - placement.position).norm(), 1e-15);
  scene.add_joint("pin", fr::JointType::revolute, origin, {}, Eigen::Vector3d::UnitZ());
  scene.add_joint("link", fr::JointType::spherical, scene.point("b", Eigen::Vector3d::Zero()),
                  scene.point("a", Eigen::Vector3d(0.4, 0.0, 0.0)));
  // By hand: the centres of mass placed, markers about them, the joints' coordinates passed in.
  fr::System by_hand;
  fr::BodyState a, b;
  a.position = placement.position + turn * com;
  a.orientation = b.orientation = turn;
  b.position = second.position + turn * com;
  by_hand.add_body("a", bar(), a);
  by_hand.add_body("b", bar(), b);
  const Eigen::VectorXd q0 = by_hand.initial_coordinates();
  const fr::Marker pin = fr::point_marker(by_hand.model(0), 0, "a", -com);
  by_hand.add_joint(fr::make_joint("pin", fr::JointType::revolute, pin,
                                   fr::ground_marker(fr::marker_position(pin, by_hand.body_coordinates(q0, 0))),
                                   Eigen::Vector3d::UnitZ(), by_hand.body_coordinates(q0, 0), Eigen::VectorXd()));
  by_hand.add_joint(fr::make_joint("link", fr::JointType::spherical, fr::point_marker(by_hand.model(1), 1, "b", -com),
                                   fr::point_marker(by_hand.model(0), 0, "a", Eigen::Vector3d(0.2, 0.0, 0.0)),
                                   Eigen::Vector3d::UnitZ(), by_hand.body_coordinates(q0, 1), by_hand.body_coordinates(q0, 0)));
  ASSERT_EQ(built.initial_coordinates(), q0);
  ASSERT_EQ(built.constraint_count(), by_hand.constraint_count());
  // The same rows everywhere: at the start and at a perturbed configuration.
  Eigen::VectorXd q = q0;
  q += 1e-3 * Eigen::VectorXd::LinSpaced(q.size(), -1.0, 1.0);
  EXPECT_EQ(built.constraints(0.0, q0), by_hand.constraints(0.0, q0));
  EXPECT_EQ(built.constraints(0.0, q), by_hand.constraints(0.0, q));
  EXPECT_EQ(built.constraint_jacobian(0.0, q), by_hand.constraint_jacobian(0.0, q));
  EXPECT_LT(built.constraints(0.0, q0).cwiseAbs().maxCoeff(), 1e-14);  // assembled as placed (coordinates near 2 m)
  // A body's initial coordinates as the layout says: [τ; vec(A)] for a GCMS rigid body (system.hpp).
  Eigen::VectorXd literal(12);
  literal << a.position, Eigen::Map<const Eigen::Matrix<double, 9, 1>>(turn.data());
  EXPECT_EQ(built.initial_body_coordinates(0), literal);
}

TEST(SceneBuilder, ADrivenJointTurnsAsItsDrive) {
  fr::System system;
  fr::SceneBuilder scene(system);
  scene.add_body("wheel", bar());
  scene.add_joint("motor", fr::JointType::driven_revolute, scene.point("wheel", Eigen::Vector3d::Zero()), {},
                  Eigen::Vector3d::UnitZ(), fr::JointDrive{2.0, 0.5});
  // Its angle row holds the body turned by φ(t) about z: at t = 1 s (past the ramp) φ = Ω (t − T/2) = 1.5 rad.
  Eigen::VectorXd q = system.initial_coordinates();
  const Eigen::Matrix3d turned = Eigen::AngleAxisd(1.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  q.segment<9>(3) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(turned.data());
  EXPECT_LT(system.constraints(1.0, q).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_GT(system.constraints(0.9, q).cwiseAbs().maxCoeff(), 0.1);  // 0.2 rad behind at 0.9 s
}

TEST(SceneBuilder, NamesWhatItCannotFind) {
  fr::System system;
  fr::SceneBuilder scene(system);
  scene.add_body("a", bar());
  try {
    (void)scene.point("b", Eigen::Vector3d::Zero());
    ADD_FAILURE() << "an unknown body was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "no body 'b' in the scene");
  }
  EXPECT_THROW(scene.add_body("a", bar()), std::invalid_argument);  // twice
  EXPECT_THROW((void)scene.interface("a", "bore"), std::invalid_argument);  // a rigid model has no interfaces
  // A revolute joint without an axis, a spherical one with one, a drive on a revolute joint, a negative ramp.
  const fr::Marker m = scene.point("a", Eigen::Vector3d::Zero());
  EXPECT_THROW(scene.add_joint("j", fr::JointType::revolute, m), std::invalid_argument);
  EXPECT_THROW(scene.add_joint("j", fr::JointType::spherical, m, {}, Eigen::Vector3d::UnitZ()), std::invalid_argument);
  EXPECT_THROW(scene.add_joint("j", fr::JointType::revolute, m, {}, Eigen::Vector3d::UnitZ(), fr::JointDrive{1.0, 0.0}),
               std::invalid_argument);
  EXPECT_THROW(scene.add_joint("j", fr::JointType::driven_revolute, m, {}, Eigen::Vector3d::UnitZ(), fr::JointDrive{1.0, -1.0}),
               std::invalid_argument);
  // A body added to the system directly: found by name, but without an input frame for points.
  system.add_body("direct", bar(), fr::BodyState{});
  EXPECT_EQ(scene.body("direct"), 1);
  EXPECT_THROW((void)scene.point("direct", Eigen::Vector3d::Zero()), std::invalid_argument);
  EXPECT_TRUE(system.joints().empty());
}

// φ̇ rises as Ω (1 − cos πt/T)/2 and φ is its integral: continuous with its rate at T, exact against a quadrature.
TEST(SceneBuilder, ADrivesRampIsSmooth) {
  const fr::JointDrive drive{10.0, 0.2};
  const auto angle = fr::drive_angle(drive);
  const auto rate = fr::drive_angle_rate(drive);
  EXPECT_EQ(angle(0.0), 0.0);
  EXPECT_EQ(rate(0.0), 0.0);
  EXPECT_NEAR(rate(0.1), 5.0, 1e-12);
  EXPECT_EQ(rate(0.3), 10.0);
  // At the end of the ramp the angle is Ω T / 2 from both sides.
  EXPECT_NEAR(angle(0.2 - 1e-12), 1.0, 1e-10);
  EXPECT_NEAR(angle(0.2), 1.0, 1e-15);
  // Simpson's rule on the rate: error (b − a) h⁴ max|f⁗| / 180 = 0.15 x (3.75e-4)⁴ x (Ω/2) (π/T)⁴ / 180 ≈ 5e-12 at
  // 400 intervals.
  const int n = 400;
  double integral = 0.0;
  for (int k = 0; k <= n; ++k) {
    const double t = 0.15 * k / n, w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
    integral += w * rate(t);
  }
  integral *= 0.15 / n / 3.0;
  EXPECT_NEAR(angle(0.15), integral, 1e-10);
  const auto at_speed = fr::drive_angle(fr::JointDrive{3.0, 0.0});
  EXPECT_EQ(at_speed(2.0), 6.0);
}

// A spring's rest length defaults to its markers' initial distance (no preload); loads follow their time shape.
TEST(SceneBuilder, SpringsAndLoads) {
  fr::System system;
  fr::SceneBuilder scene(system);
  fr::Placement at;
  at.position = Eigen::Vector3d(0.0, -0.3, 0.0);
  scene.add_body("a", bar(), at);
  scene.add_spring("hang", fr::SceneBuilder::ground(Eigen::Vector3d(0.0, 0.1, 0.0)), scene.point("a", Eigen::Vector3d::Zero()), 100.0);
  scene.add_spring("preloaded", fr::SceneBuilder::ground(Eigen::Vector3d::Zero()), scene.point("a", Eigen::Vector3d::Zero()),
                   100.0, 1.0, 0.25);
  scene.add_force(scene.point("a", Eigen::Vector3d::Zero()), Eigen::Vector3d(0.0, 0.0, 2.0), fr::LoadShape{0.5, 0.0});
  const Eigen::VectorXd q = system.initial_coordinates(), v = Eigen::VectorXd::Zero(q.size());
  // Only the preloaded spring pulls (0.05 m stretched x 100 N/m = 5 N up); the force is at half its ramp at 0.25 s.
  const Eigen::VectorXd f = system.forces(0.25, q, v);
  EXPECT_NEAR(f(1), 5.0, 1e-12);
  EXPECT_NEAR(f(2), 1.0, 1e-15);
  EXPECT_NEAR(system.energies(q, v).springs, 0.5 * 100.0 * 0.05 * 0.05, 1e-15);
  const auto wave = fr::load_factor(fr::LoadShape{0.0, 2.0});
  EXPECT_NEAR(wave(0.125), 1.0, 1e-15);  // sin(2π 2 0.125) = sin(π/2)
}
