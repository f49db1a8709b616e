// Rigid bodies: stiff springs in the Newton matrix, the floating-frame rigid body against Newton and the GCMS body,
// and the joints' curvature (rigid_pendulum_test.cpp: the pendulum).
#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>
#include "rigid_pendulum_helpers.hpp"

namespace fr = flexbody::runtime;
using namespace rigid_pendulum;

TEST(RigidBody, StiffSpringsConvergeWithTheirTangentInTheNewtonMatrix) {
  // A bar on a spring-damper to ground with k h² = 10 m, a stiff bushing at a coarse step. Without the spring's
  // tangent in the Newton matrix the iteration contracts at about k h²/(4 m) and stops converging from k h² ≈ 3 m
  // (measured before: 11 iterations per step at k h² = m). With it, a fresh matrix converges quadratically: two
  // iterations per step at the centre of mass, 2.9 at the bar's end, where the spring also turns the bar at
  // ω h ≈ 5 and the orthogonality rows' curvature counts. The kept matrix (the default) goes stale as the spring's
  // direction turns (a rate of about 1e-3 against a first correction of the whole oscillation's amplitude):
  // measured 3.1 and 4.1 iterations per step. Both Newton variants give the same solution.
  const fr::BodyModel model = rigid_bar();
  const double h = 1e-3;
  for (const double offset : {0.0, kLength / 2}) {
    SCOPED_TRACE(offset);
    std::vector<Eigen::VectorXd> finals;
    for (const fr::NewtonMatrix matrix : {fr::NewtonMatrix::constant_core, fr::NewtonMatrix::dense}) {
      fr::System system;
      fr::BodyState state;
      state.velocity = Eigen::Vector3d(0.1, 0.05, 0);
      state.angular_velocity = Eigen::Vector3d(0, 0, 0.3);
      const int bar = system.add_body("bar", model, state);
      fr::SpringDamper spring;
      spring.name = "bushing";
      spring.first = fr::point_marker(model, bar, "bar", Eigen::Vector3d(offset, 0, 0));
      spring.second = fr::ground_marker(Eigen::Vector3d(offset + 0.1, 0.02, 0));
      spring.stiffness = 10.0 * kMass / (h * h);
      spring.damping = 50.0;
      spring.rest_length = (spring.second.ground_point - Eigen::Vector3d(offset, 0, 0)).norm();  // no preload
      system.add_spring(spring);
      fr::GeneralizedAlphaOptions options;
      options.step = h;
      options.rho_infinity = 0.8;
      options.newton_matrix = matrix;
      fr::GeneralizedAlpha integrator(system, options);
      for (int k = 0; k < 200; ++k) integrator.step();
      EXPECT_LE(static_cast<double>(integrator.total_iterations()) / 200.0, offset == 0.0 ? 3.5 : 4.5);
      finals.push_back(integrator.coordinates());
    }
    EXPECT_LT((finals[0] - finals[1]).cwiseAbs().maxCoeff(), 1e-8);  // the same solution to the Newton tolerance
  }
}

// The same bar in floating-frame coordinates [τ; p] (ffrf_model.hpp with no modes): a torque and a joint reaction
// reach it through the Euler parameters (Q_p = 2 Ḡᵀ Aᵀ T; the moment ½ E(p) Q_p), with the results of the GCMS bar.
TEST(FloatingFrameRigidBody, TorqueAndJointReactionActAsNewtonSays) {
  fr::BodyModel model = rigid_bar();
  model.mode_coefficients.resize(0, 0);
  model.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(model, fr::FloatingFrame::mean_axis));
  {
    fr::System system;
    const int bar = system.add_body("bar", model, fr::BodyState{});
    system.add_torque({fr::point_marker(model, bar, "bar", Eigen::Vector3d::Zero()), [](double) { return Eigen::Vector3d(0, 0, 2.0); }});
    fr::GeneralizedAlphaOptions options;
    options.step = 1e-3;
    fr::GeneralizedAlpha integrator(system, options);
    for (int i = 0; i < 100; ++i) integrator.step();
    const double izz = kMass * (kLength * kLength + kWidth * kWidth) / 12.0;
    // ω̇ = T / I_zz, integrated exactly (a uniform angular acceleration); the tolerance as for the GCMS bar.
    const Eigen::Vector3d omega = system.angular_velocity(bar, integrator.coordinates(), integrator.velocities());
    EXPECT_NEAR(omega.z(), 2.0 / izz * 0.1, 1e-6 * 2.0 / izz * 0.1);
    EXPECT_LT(omega.head<2>().norm(), 1e-12);
  }
  {
    fr::System system;
    fr::BodyState state;
    state.position = Eigen::Vector3d(kLength / 2, 0, 0);
    const int bar = system.add_body("bar", model, state);
    const fr::Marker end = fr::point_marker(system.model(bar), bar, "bar", Eigen::Vector3d(-kLength / 2, 0, 0));
    system.add_joint(fr::make_joint("clamp", fr::JointType::fixed, end, fr::ground_marker(Eigen::Vector3d::Zero()),
                                    Eigen::Vector3d::UnitZ(), system.initial_coordinates(), Eigen::VectorXd()));
    system.set_gravity(Eigen::Vector3d(0, -kGravity, 0));
    fr::GeneralizedAlphaOptions options;
    options.step = 1e-3;
    fr::GeneralizedAlpha integrator(system, options);
    const double weight = kMass * kGravity;
    for (int k = 0; k < 2; ++k) {  // statics: F = −m g, M = m g L/2 about the end (round-off only)
      const fr::JointReaction r = system.joint_reaction(0, integrator.time(), integrator.coordinates(), integrator.multipliers());
      EXPECT_LT((r.force - Eigen::Vector3d(0, weight, 0)).norm(), 1e-12 * weight);
      EXPECT_LT((r.moment - Eigen::Vector3d(0, 0, weight * kLength / 2)).norm(), 1e-12 * weight * kLength);
      integrator.step();
    }
  }
}

// The review's case against a test that only looks along z at p = (1, 0, 0, 0): the bar started turned by 37° about
// (1, 2, 3) and spinning about an oblique axis, hinged at one end by a revolute joint whose axis is oblique too, under
// gravity and a torque about x at the hinge. The floating-frame body (Euler parameters: Q_p = 2 Ḡᵀ Aᵀ T, the reaction
// moment ½ E(p) Q_p) and the GCMS body (vec(A)) are the same rigid body in two sets of coordinates: the free end's
// path and the joint's force and moment must agree to the integrators' discretisation of the two (O(h²); measured
// 2.1e-9, 1.6e-9 and 9e-10 of the values at h = 1e-4 s), where a missing Aᵀ or E swapped for Ḡ is wrong in the
// first digit.
TEST(FloatingFrameRigidBody, AnObliqueTorqueAndHingeAgreeWithTheGcmsBody) {
  fr::BodyModel gcms = rigid_bar();
  fr::BodyModel ffrf = gcms;
  ffrf.mode_coefficients.resize(0, 0);
  ffrf.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(ffrf, fr::FloatingFrame::mean_axis));
  const Eigen::Matrix3d turned = Eigen::AngleAxisd(37.0 * std::numbers::pi / 180.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  struct Run {
    std::vector<Eigen::Vector3d> tip, force, moment;
  };
  auto run = [&](const fr::BodyModel& model) {
    fr::System system;
    fr::BodyState state;
    state.orientation = turned;
    state.position = turned * Eigen::Vector3d(kLength / 2, 0, 0);  // the end −L/2 at the origin
    const Eigen::Vector3d axis = Eigen::Vector3d(0.2, 0.3, 1.0).normalized();
    state.angular_velocity = 1.5 * axis;
    state.velocity = state.angular_velocity.cross(state.position);
    const int bar = system.add_body("bar", model, state);
    const fr::Marker end = fr::point_marker(model, bar, "bar", Eigen::Vector3d(-kLength / 2, 0, 0));
    const fr::Marker tip = fr::point_marker(model, bar, "bar", Eigen::Vector3d(kLength / 2, 0, 0));
    system.add_joint(fr::make_joint("hinge", fr::JointType::revolute, end, fr::ground_marker(Eigen::Vector3d::Zero()),
                                    axis, system.initial_coordinates(), Eigen::VectorXd()));
    system.add_torque({end, [](double) { return Eigen::Vector3d(0.8, 0, 0); }});
    system.set_gravity(Eigen::Vector3d(0, -kGravity, 0));
    fr::GeneralizedAlphaOptions options;
    options.step = 1e-4;
    options.tolerance = 1e-10;
    fr::GeneralizedAlpha integrator(system, options);
    Run out;
    for (int k = 0; k < 2000; ++k) {
      integrator.step();
      if (k % 100 != 99) continue;
      out.tip.push_back(fr::marker_position(tip, system.body_coordinates(integrator.coordinates(), bar)));
      const fr::JointReaction r = system.joint_reaction(0, integrator.time(), integrator.coordinates(), integrator.multipliers());
      out.force.push_back(r.force);
      out.moment.push_back(r.moment);
    }
    return out;
  };
  const Run a = run(gcms), b = run(ffrf);
  double travel = 0.0, force = 0.0, moment = 0.0, d_tip = 0.0, d_force = 0.0, d_moment = 0.0;
  for (std::size_t k = 0; k < a.tip.size(); ++k) {
    travel = std::max(travel, (a.tip[k] - a.tip.front()).norm());
    force = std::max(force, a.force[k].norm());
    moment = std::max(moment, a.moment[k].norm());
    d_tip = std::max(d_tip, (a.tip[k] - b.tip[k]).norm());
    d_force = std::max(d_force, (a.force[k] - b.force[k]).norm());
    d_moment = std::max(d_moment, (a.moment[k] - b.moment[k]).norm());
  }
  ASSERT_GT(travel, 0.05 * kLength);
  ASSERT_GT(moment, 0.1);  // the hinge carries the torque's and the gyroscopic moments off its axis
  EXPECT_LT(d_tip, 1e-6 * travel) << d_tip;
  EXPECT_LT(d_force, 1e-6 * force) << d_force << " of " << force;
  EXPECT_LT(d_moment, 1e-6 * moment) << d_moment << " of " << moment;
}

// The Newton matrix's curvature of the joints (System::add_joint_hessian, by differences of the joints' Jacobians)
// against second differences of λᵀΦ(q) itself, over every coordinate: two GCMS bars and a floating-frame bar joined to
// each other and to ground by driven, prismatic, fixed and revolute joints, at a state off the assembly (every
// coordinate moved by up to 0.05, A off SO(3)), with random multipliers. Independent of the Jacobians: only residuals
// are differenced. Their agreement bounds both the assembly of the blocks and the Jacobians' consistency.
TEST(JointCurvature, TheConstraintHessianHoldsTheJointsSecondDerivatives) {
  fr::BodyModel gcms = rigid_bar();
  fr::BodyModel ffrf = gcms;
  ffrf.mode_coefficients.resize(0, 0);
  ffrf.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(ffrf, fr::FloatingFrame::mean_axis));
  fr::System system;
  fr::BodyState s1, s2, s3;
  s2.position = Eigen::Vector3d(kLength, 0, 0);
  s3.position = Eigen::Vector3d(2 * kLength, 0, 0);
  s3.orientation = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0, 0, 1)).toRotationMatrix();
  const int a = system.add_body("a", gcms, s1), b = system.add_body("b", gcms, s2), c = system.add_body("c", ffrf, s3);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  auto q_of = [&](int body) { return Eigen::VectorXd(system.body_coordinates(q0, body)); };
  auto end = [&](int body, double x) { return fr::point_marker(system.model(body), body, "bar", Eigen::Vector3d(x, 0, 0)); };
  const Eigen::Vector3d oblique = Eigen::Vector3d(0.3, 0.2, 1.0).normalized();
  system.add_joint(fr::make_joint("drive", fr::JointType::driven_revolute, end(a, kLength / 2), end(b, -kLength / 2),
                                  oblique, q_of(a), q_of(b), [](double t) { return 2.0 * t; }));
  system.add_joint(fr::make_joint("slide", fr::JointType::prismatic, end(b, kLength / 2), end(c, -kLength / 2),
                                  Eigen::Vector3d(1, 0.1, 0).normalized(), q_of(b), q_of(c)));
  system.add_joint(fr::make_joint("weld", fr::JointType::fixed, end(c, kLength / 2),
                                  fr::ground_marker(fr::marker_position(end(c, kLength / 2), q_of(c))), oblique, q_of(c),
                                  Eigen::VectorXd()));
  system.add_joint(fr::make_joint("hinge", fr::JointType::revolute, end(a, -kLength / 2),
                                  fr::ground_marker(Eigen::Vector3d(-kLength / 2, 0, 0)), Eigen::Vector3d::UnitZ(), q_of(a),
                                  Eigen::VectorXd()));
  std::srand(5);
  const Eigen::VectorXd q = q0 + 0.05 * Eigen::VectorXd::Random(q0.size());
  const Eigen::VectorXd lambda = Eigen::VectorXd::Random(system.constraint_count());
  const double t = 0.4;  // the drive between the bars at φ = 0.8 rad: its angle row's curvature turns with φ(t)
  const Eigen::MatrixXd analytic = system.constraint_hessian(t, q, lambda);
  const Eigen::Index n = q.size();
  auto f = [&](const Eigen::VectorXd& x) { return lambda.dot(system.constraints(t, x)); };
  Eigen::MatrixXd numeric(n, n);
  const double h = 1e-4;
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index k = 0; k < n; ++k) {
      Eigen::VectorXd pp = q, pm = q, mp = q, mm = q;
      pp(i) += h, pp(k) += h;
      pm(i) += h, pm(k) -= h;
      mp(i) -= h, mp(k) += h;
      mm(i) -= h, mm(k) -= h;
      numeric(i, k) = (f(pp) - f(pm) - f(mp) + f(mm)) / (4 * h * h);
    }
  ASSERT_GT(numeric.cwiseAbs().maxCoeff(), 0.1);
  // Second differences of a polynomial of degree ≤ 4 at h = 1e-4: O(h²) and round-off ε |f| / h² ≈ 1e-8 of the entries.
  EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-6 * numeric.cwiseAbs().maxCoeff());
  // The joints' part is what the test sees: with their multipliers zeroed the Hessian misses most of it.
  Eigen::VectorXd bodies_only = lambda;
  bodies_only.tail(system.constraint_count() - system.joint_row(0)).setZero();
  const Eigen::MatrixXd without = system.constraint_hessian(t, q, bodies_only);
  EXPECT_GT((without - numeric).cwiseAbs().maxCoeff(), 0.1 * numeric.cwiseAbs().maxCoeff());
}
