// The stabilised index-2 form of generalized-α on the cases a review of its first version (77a5e2a) found: a driven
// joint far from t = 0, and two bodies of very different size joined together.
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace fr = flexbody::runtime;

namespace {

// A rigid box of mass m and edges `edges`: J = ∫ x xᵀ dm = m diag(edges²)/12.
fr::BodyModel box(double mass, const Eigen::Vector3d& edges) {
  fr::BodyModel model;
  model.source = "box";
  model.mass = mass;
  model.mass_matrix = Eigen::Matrix4d::Zero();
  model.mass_matrix(0, 0) = mass;
  model.mass_matrix.block<3, 3>(1, 1) = mass / 12.0 * edges.cwiseProduct(edges).asDiagonal();
  model.stiffness.resize(0, 0);
  model.tisserand.resize(3, 0);
  return model;
}

// The largest |ω − 10 rad/s| of a 1 m bar driven about z at 10 rad/s from t0, over 500 steps of 1 ms.
double driven_speed_error(double t0, fr::ConstraintForm form) {
  const fr::BodyModel bar = box(10.0, Eigen::Vector3d(1.0, 0.1, 0.1));
  fr::System system;
  fr::BodyState state;
  state.position = Eigen::Vector3d(0.5, 0, 0);
  const int b = system.add_body("bar", bar, state);
  system.add_joint(fr::make_joint("drive", fr::JointType::driven_revolute,
                                  fr::point_marker(bar, b, "bar", Eigen::Vector3d(-0.5, 0, 0)),
                                  fr::ground_marker(Eigen::Vector3d::Zero()), Eigen::Vector3d::UnitZ(),
                                  system.initial_coordinates(), Eigen::VectorXd(),
                                  [t0](double t) { return 10.0 * (t - t0); }));
  fr::GeneralizedAlphaOptions options;
  options.step = 1e-3;
  options.constraints = form;
  fr::GeneralizedAlpha integrator(system, options, t0);
  double worst = 0.0;
  for (int i = 0; i < 500; ++i) {
    integrator.step();
    const Eigen::Matrix3d w = fr::orientation_of(integrator.velocities()) * fr::orientation_of(integrator.coordinates()).transpose();
    worst = std::max(worst, std::abs(0.5 * (w(1, 0) - w(0, 1)) - 10.0));
  }
  return worst;
}

}  // namespace

// Φ_t of a driven joint comes from central differences in t. A step ε^⅓ (1 + |t|) let the truncation error grow as
// t²: 6.1e-4 rad/s at t0 = 1000 s (review of 77a5e2a). With ∛(ε (1 + |t|)), measured: 8.0e-9, 1.3e-7, 6.1e-7 rad/s
// at t0 = 0, 100, 1000 s, the rounding of the angle 10 (t − t0) growing like ∛t. The index-3 form meets no velocity
// rows: its speed is off by the discretisation, 1.7e-4 rad/s, at any t0.
TEST(StabilizedIndex2, DrivenJointFarFromTimeZero) {
  EXPECT_LT(driven_speed_error(0.0, fr::ConstraintForm::stabilized_index2), 5e-8);
  EXPECT_LT(driven_speed_error(100.0, fr::ConstraintForm::stabilized_index2), 1e-6);
  EXPECT_LT(driven_speed_error(1000.0, fr::ConstraintForm::stabilized_index2), 3e-6);
  EXPECT_GT(driven_speed_error(1000.0, fr::ConstraintForm::index3), 1e-4);
}

// A 1 mm steel cube on a spherical joint at the tip of a 100 m steel bar pinned to ground, falling under gravity.
// With the position correction weighted by the coordinates' scales alone (scale², r² = 833 m² for τ of the big bar,
// 1.7e-7 m² for the cube's), the correction moved the big bar and Newton repeated a correction of 250 round-off
// floors until it failed at t = 0.0035 s; weighted by 1/(m r²) per body the light body takes it. Measured: 0.2 s in
// 4.2 iterations per step (the index-3 form: 3.1).
TEST(StabilizedIndex2, ALightBodyOnAHeavyOneTakesThePositionCorrection) {
  const double length = 100.0, size = 1e-3;
  const fr::BodyModel bar = box(7850.0 * length * 0.25, Eigen::Vector3d(length, 0.5, 0.5));
  const fr::BodyModel cube = box(7850.0 * size * size * size, Eigen::Vector3d::Constant(size));
  fr::System system;
  fr::BodyState at_bar, at_cube;
  at_bar.position = Eigen::Vector3d(length / 2, 0, 0);
  at_cube.position = Eigen::Vector3d(length + size / 2, 0, 0);
  const int b0 = system.add_body("bar", bar, at_bar), b1 = system.add_body("cube", cube, at_cube);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  system.add_joint(fr::make_joint("pivot", fr::JointType::revolute,
                                  fr::point_marker(bar, b0, "bar", Eigen::Vector3d(-length / 2, 0, 0)),
                                  fr::ground_marker(Eigen::Vector3d::Zero()), Eigen::Vector3d::UnitZ(),
                                  system.body_coordinates(q0, b0), Eigen::VectorXd()));
  system.add_joint(fr::make_joint("ball", fr::JointType::spherical,
                                  fr::point_marker(bar, b0, "bar", Eigen::Vector3d(length / 2, 0, 0)),
                                  fr::point_marker(cube, b1, "cube", Eigen::Vector3d(-size / 2, 0, 0)),
                                  Eigen::Vector3d::UnitZ(), system.body_coordinates(q0, b0),
                                  system.body_coordinates(q0, b1)));
  system.set_gravity(Eigen::Vector3d(0, -9.81, 0));
  fr::GeneralizedAlphaOptions options;
  options.step = 1e-4;
  fr::GeneralizedAlpha integrator(system, options);
  EXPECT_NO_THROW(while (integrator.time() < 0.2 - 0.5e-4) integrator.step());
  EXPECT_NEAR(integrator.time(), 0.2, 1e-9);
  // The joints hold: the constraint residuals are round-off of 100 m.
  EXPECT_LT(system.constraints(integrator.time(), integrator.coordinates()).cwiseAbs().maxCoeff(), 1e-11);
}

// step_to ends a run on its end time with a shortened last step. Far from t = 0 the time reached after whole steps
// carries the rounding of t0 + k h, a few ε |t| (1.8e-12 s at 1.2e4 s, 6e-9 of a 0.3 ms step): a last step that
// long must be accepted as a whole step (review of 1ffb6fd: a fixed slack of 1e-9 h refused it beyond ~1e7 steps).
TEST(StepTo, AcceptsTheRoundingOfTheTimeFarFromZero) {
  const fr::BodyModel bar = box(10.0, Eigen::Vector3d(1.0, 0.1, 0.1));
  fr::System system;
  (void)system.add_body("bar", bar, fr::BodyState{});
  system.set_gravity(Eigen::Vector3d(0, 0, -9.81));
  fr::GeneralizedAlphaOptions options;
  options.step = 3e-4;
  const double t0 = 1.2e4;
  fr::GeneralizedAlpha integrator(system, options, t0);
  for (int i = 0; i < 3; ++i) integrator.step();
  const double t_end = integrator.time() + options.step + 2e-12;  // one or two ulps of t beyond a whole step
  ASSERT_GT(t_end - integrator.time(), options.step * (1.0 + fr::GeneralizedAlpha::kStepToSlack));
  integrator.step_to(t_end);
  EXPECT_EQ(integrator.time(), t_end);
  // Free fall from rest: τ_z = −g (t − t0)² / 2, which generalized-α integrates exactly (constant acceleration).
  const double fall = t_end - t0;
  EXPECT_NEAR(integrator.coordinates()(2), -0.5 * 9.81 * fall * fall, 1e-12);
}
