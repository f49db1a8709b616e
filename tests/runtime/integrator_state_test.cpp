// The integrator's state (issue 31: restarts and users' controllers): a run set back to an earlier state goes on as
// it went the first time, and an exception from the scene's own functions (a force's) passes through and leaves the
// last completed step, from which the run can go on.
#include "rigid_pendulum_helpers.hpp"

#include <stdexcept>

using namespace rigid_pendulum;

TEST(IntegratorState, ARunSetBackGoesOnAsBefore) {
  fr::System system = pendulum(rigid_bar());
  fr::GeneralizedAlphaOptions options;
  options.step = 1e-3;
  fr::GeneralizedAlpha integrator(system, options);
  for (int k = 0; k < 100; ++k) integrator.step();
  const fr::IntegratorState saved = integrator.state();
  EXPECT_EQ(saved.time, integrator.time());
  for (int k = 0; k < 50; ++k) integrator.step();
  const Eigen::VectorXd first = integrator.coordinates();
  const double first_time = integrator.time();
  integrator.set_state(saved);
  EXPECT_EQ(integrator.time(), saved.time);
  EXPECT_TRUE(integrator.coordinates() == saved.q);
  for (int k = 0; k < 50; ++k) integrator.step();
  EXPECT_NEAR(integrator.time(), first_time, 1e-15);  // t0 + k h from the state's time
  // The same motion up to the Newton iteration's error: the second time starts with a fresh Newton matrix where the
  // first kept one (modified Newton). The tolerance's iteration error is 1e-6 of a step's predictor distance, about
  // 1e-6 × h² |q̈| ≈ 1e-11 per step here; measured 1.3e-11 after 50 steps (deterministic: the same bits every run).
  EXPECT_LT((integrator.coordinates() - first).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(IntegratorState, ARefusedStateNamesItsEntry) {
  fr::System system = pendulum(rigid_bar());
  fr::GeneralizedAlpha integrator(system, fr::GeneralizedAlphaOptions{});
  fr::IntegratorState s = integrator.state();
  s.v.conservativeResize(s.v.size() - 1);
  try {
    integrator.set_state(s);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "generalized-alpha state: v has 11 entries, the system 12");
  }
  const fr::IntegratorState before = integrator.state();
  s = before;
  s.q(0) += 1.0;
  s.lambda(0) = std::nan("");
  EXPECT_THROW(integrator.set_state(s), std::invalid_argument);
  EXPECT_TRUE(integrator.state().q == before.q);  // a refused state changes nothing
}

TEST(IntegratorState, AThrowingForcePassesThroughAndLeavesTheLastStep) {
  // The pendulum pushed sideways at its tip by a force that throws once, during the 31st step.
  auto run = [](bool throw_once) {
    fr::System system = pendulum(rigid_bar());
    bool armed = throw_once;
    fr::PointForce push;
    push.marker = fr::point_marker(system.model(0), 0, "bar", Eigen::Vector3d(kLength / 2, 0, 0));
    push.force = [&armed](double t) -> Eigen::Vector3d {
      if (armed && t > 0.0305) throw std::runtime_error("the controller's sensor is off");
      return Eigen::Vector3d(0.0, 0.0, 2.0 * t);
    };
    system.add_force(push);
    fr::GeneralizedAlpha integrator(system, fr::GeneralizedAlphaOptions{});
    for (int k = 0; k < 30; ++k) integrator.step();
    const fr::IntegratorState before = integrator.state();
    if (throw_once) {
      EXPECT_THROW(integrator.step(), std::runtime_error);
      const fr::IntegratorState after = integrator.state();
      EXPECT_EQ(after.time, before.time);
      EXPECT_TRUE(after.q == before.q && after.v == before.v && after.lambda == before.lambda);
      armed = false;
      // The Newton matrix the failed step was using is not trusted: the next step builds one.
      const long built = integrator.factorizations();
      integrator.step();
      EXPECT_EQ(integrator.factorizations(), built + 1);
      for (int k = 0; k < 29; ++k) integrator.step();
      return integrator.coordinates();
    }
    for (int k = 0; k < 30; ++k) integrator.step();
    return integrator.coordinates();
  };
  const Eigen::VectorXd once = run(true), never = run(false);
  // The fresh Newton matrix after the failure: as above (measured 1.9e-11).
  EXPECT_LT((once - never).cwiseAbs().maxCoeff(), 1e-10);
}
