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
  scene.add_joint("pin", fr::JointType::revolute, scene.point("a", Eigen::Vector3d::Zero()), {}, Eigen::Vector3d::UnitZ());
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
  EXPECT_LT(built.constraints(0.0, q0).cwiseAbs().maxCoeff(), 1e-15);  // assembled as placed
  for (int k = 0; k < 2; ++k) EXPECT_EQ(built.initial_body_coordinates(k), built.body_coordinates(q0, k));
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
  // Simpson's rule on the rate (a smooth integrand: error of order h⁴ f'''' ≈ 1e-12 at 200 intervals).
  const int n = 200;
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
