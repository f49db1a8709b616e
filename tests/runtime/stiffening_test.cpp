// Geometric stiffening at run time (issue 29): a cantilever spinning about its root, made by fbprep with
// --geometric-stiffness, against Southwell's coefficients. Its first bending frequency in the rotating frame follows
// f² = f₀² + S Ω² out of the plane of rotation (flapwise) and f² = f₀² + (S − 1) Ω² in it (lead-lag), with S = 1.1933
// for a uniform cantilever with no hub radius (Southwell; Bhat 1986 and Wright et al. 1982 tabulate it). Without the
// prestress the model has the spin softening −Ω² of the rotating frame and none of the stiffening.
#include "calculix.hpp"
#include "cli_run.hpp"
#include "flexbody/format/body_file.hpp"
#include "flexbody/runtime/body_model.hpp"
#include "flexbody/runtime/damping.hpp"
#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/prestress.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"
#include "test_meshes.hpp"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>
#include "stiffening_helpers.hpp"

namespace fr = flexbody::runtime;
using namespace stiffening;

TEST(GeometricStiffening, TheRotatingBeamReference) {
  EXPECT_NEAR(beam_frequency(0.0, false), 3.5160, 1e-4);  // (β₁L)² of the clamped-free beam
  // Southwell's coefficient is the slope of ω² in Ω² at small spin: 1.1933 flapwise, 0.1933 in the plane.
  const double rest = beam_frequency(0.0, false), small = 0.01 * rest;
  EXPECT_NEAR((std::pow(beam_frequency(small, false), 2) - rest * rest) / (small * small), kSouthwell, 2e-4);
  EXPECT_NEAR((std::pow(beam_frequency(small, true), 2) - rest * rest) / (small * small), kSouthwell - 1.0, 2e-4);
  // At Ω = 2 ω₀ the mode shape has changed with the spin, and Southwell's straight line in Ω² is 1.4 % above the
  // beam's frequency (2.3692 ω₀ against √(1 + 4 S) = 2.4028 ω₀); Hodges & Rutkowski (1981) tabulate 8.2996 at
  // Ω = 7 √(EI/(m L⁴)), which this reproduces.
  EXPECT_NEAR(beam_frequency_ratio(2.0, false), 2.3692, 1e-4);
  EXPECT_NEAR(beam_frequency(7.0, false), 8.2996, 1e-4);
}

// The three formulations on the fbprep beam, spun at 0.5 to 2 times its first (flapwise) frequency, against the
// rotating beam (the ratio ω(Ω)/ω(0) of the Euler-Bernoulli beam above, times the frequency the body shows at rest,
// so that the mesh's and the basis's error at rest cancel). Measured: within 0.12 % everywhere (issue 29 asks for
// 1 % against Southwell's law; the law itself is 1.4 % off at 2 ω₁, where the rotating beam is the reference). The
// frequency measurement alone is good to about 3e-4 (ten periods' zero crossings; trapezoidal rule (ω h)²/12).
TEST(GeometricStiffening, ACantileverSpinningAboutItsRootMeetsTheRotatingBeam) {
  for (Formulation formulation : {Formulation::gcms, Formulation::ffrf_mean_axis, Formulation::ffrf_root}) {
    for (Direction direction : {Direction::flapwise, Direction::lead_lag}) {
      SCOPED_TRACE(static_cast<int>(formulation) * 10 + static_cast<int>(direction));
      const bool lag = direction == Direction::lead_lag;
      const double f0 = measured_frequency(formulation, direction, 0.0, lag ? 157.0 : 105.0);
      EXPECT_NEAR(f0, lag ? 157.5 : 105.1, 0.5);  // the same modes, whatever the formulation
      for (double ratio : {0.5, 1.0, 1.5, 2.0}) {
        const double spin = ratio * 105.0;  // in units of the lowest (flapwise) frequency
        const double expected = f0 * beam_frequency_ratio(spin / f0, lag);
        const double measured = measured_frequency(formulation, direction, spin, expected);
        EXPECT_NEAR(measured / expected, 1.0, 0.005) << "at " << ratio << " omega_1";
      }
    }
  }
  // Without the prestress the answer depends on the frame the deformation is measured from, because what is left
  // out is that frame's foreshortening. In the root frame it is the classic linear model (Kane, Ryan & Banerjee
  // 1987): flapwise the frequency at rest, in the plane √(ω₀² − Ω²). In the mean-axis frame (the GCMS's) part of the
  // stiffening happens to be there: measured 145.0 and 154.3 rad/s at Ω = ω₁ against the rotating beam's 155.1 and
  // 164.0. With the prestress all three agree (above).
  const double spin = 105.0;
  EXPECT_NEAR(measured_frequency(Formulation::ffrf_root, Direction::flapwise, spin, 105.0, false) / 105.1, 1.0, 0.005);
  EXPECT_NEAR(measured_frequency(Formulation::ffrf_root, Direction::lead_lag, spin, 118.0, false) /
                  std::sqrt(157.5 * 157.5 - spin * spin), 1.0, 0.005);
  EXPECT_LT(measured_frequency(Formulation::gcms, Direction::flapwise, spin, 145.0, false) / 155.1, 0.95);
  EXPECT_LT(measured_frequency(Formulation::gcms, Direction::lead_lag, spin, 154.0, false) / 164.0, 0.95);
}

namespace {

// The spin-up of Kane, Ryan & Banerjee (1987), on the beam above: driven about y at its root (so that it bends in the
// plane of rotation about its thin direction, z, at ω₁ = 105 rad/s), from rest to Ω_s = 1.5 ω₁ along
// Ω(t) = Ω_s (t/T − sin(2π t/T)/(2π)) over T = 1.5 s, then held for 0.3 s. The rotating frame's tip deflection
// along z, sampled every millisecond.
struct SpinUp {
  std::vector<double> deflection;
  std::string failure;
};

SpinUp spin_up(Formulation formulation, bool stiffening, double radians_per_step, bool default_guard = true) {
  const fr::BodyModel model = model_of(formulation, stiffening);
  constexpr double kFinal = 1.5 * 105.0, kRamp = 1.5, kEnd = 1.8;
  auto angle = [](double t) {  // ∫ Ω dt
    if (t >= kRamp) return kFinal * (t - 0.5 * kRamp);
    const double c = 2 * std::numbers::pi / kRamp;
    return kFinal / kRamp * (0.5 * t * t + (std::cos(c * t) - 1.0) / (c * c));
  };
  fr::System system;
  const int b = system.add_body("beam", model, fr::BodyState{});
  const Eigen::VectorXd q0 = system.initial_coordinates();
  const fr::Marker root = fr::interface_marker(model, b, "beam", "root");
  const fr::Marker tip = fr::interface_marker(model, b, "beam", "tip");
  const Eigen::Vector3d hub = fr::marker_position(root, q0);
  system.add_joint(fr::make_joint("hub", fr::JointType::driven_revolute, root, fr::ground_marker(hub),
                                  Eigen::Vector3d::UnitY(), q0, Eigen::VectorXd(), angle));
  fr::GeneralizedAlphaOptions options;
  options.rho_infinity = 0.9;
  const int per_sample = static_cast<int>(std::ceil(1e-3 * kFinal / radians_per_step));  // whole steps per millisecond
  options.step = 1e-3 / per_sample;
  if (!default_guard) options.spin_warning = options.spin_limit = 0.0;
  fr::GeneralizedAlpha integrator(system, options);
  SpinUp result;
  try {
    for (int k = 1; k <= static_cast<int>(std::lround(kEnd / 1e-3)); ++k) {
      for (int i = 0; i < per_sample; ++i) integrator.step();
      const Eigen::Vector3d p = fr::marker_position(tip, system.body_coordinates(integrator.coordinates(), b)) - hub;
      const double phi = angle(integrator.time());  // about y: the rotating frame's z axis is (sin φ, 0, cos φ)
      result.deflection.push_back(std::sin(phi) * p.x() + std::cos(phi) * p.z());
    }
  } catch (const fr::StepFailure& e) {
    result.failure = e.what();
  }
  return result;
}

// The largest difference over the reference's largest deflection.
double relative_error(const SpinUp& run, const SpinUp& reference) {
  double error = 0.0, largest = 0.0;
  for (std::size_t k = 0; k < reference.deflection.size(); ++k) {
    largest = std::max(largest, std::abs(reference.deflection[k]));
    if (k < run.deflection.size()) error = std::max(error, std::abs(run.deflection[k] - reference.deflection[k]));
  }
  return error / largest;
}

}  // namespace

// Issue 29's criterion: the spin-up runs through with stiffening at two steps, within 3 % of a converged stiffened
// reference (here 0.005 rad per step at full speed). Measured, GCMS: 5.5e-4 of the largest deflection (19.6 mm) at
// 0.04 rad per step and 1.3e-4 at 0.02, a ratio of 4.2 (second order); the FFRF in the root frame, another
// formulation with other kinematics, 1.1e-3 from the GCMS reference. The linear model is stopped by the spin guard at
// half the first frequency, and without the guard it leaves the small-deformation range at 0.9 s (Ω = 1.04 ω₁).
TEST(GeometricStiffening, ASpinUpToOneAndAHalfTimesTheFirstFrequencyRunsThrough) {
  const SpinUp reference = spin_up(Formulation::gcms, true, 0.005);
  ASSERT_TRUE(reference.failure.empty()) << reference.failure;
  const SpinUp coarse = spin_up(Formulation::gcms, true, 0.04), fine = spin_up(Formulation::gcms, true, 0.02);
  EXPECT_TRUE(coarse.failure.empty()) << coarse.failure;
  EXPECT_TRUE(fine.failure.empty()) << fine.failure;
  EXPECT_LT(relative_error(coarse, reference), 2e-3);
  EXPECT_LT(relative_error(fine, reference), 5e-4);
  EXPECT_GT(relative_error(coarse, reference) / relative_error(fine, reference), 3.0);
  const SpinUp ffrf = spin_up(Formulation::ffrf_root, true, 0.02);
  EXPECT_TRUE(ffrf.failure.empty()) << ffrf.failure;
  EXPECT_LT(relative_error(ffrf, reference), 3e-3);

  const SpinUp guarded = spin_up(Formulation::ffrf_root, false, 0.02);
  EXPECT_NE(guarded.failure.find("has no centrifugal stiffening"), std::string::npos) << guarded.failure;
  EXPECT_NE(guarded.failure.find("(limit: 0.5 of it)"), std::string::npos) << guarded.failure;
  const SpinUp linear = spin_up(Formulation::ffrf_root, false, 0.02, false);
  EXPECT_NE(linear.failure.find("left the small-deformation range"), std::string::npos) << linear.failure;
}

// The weights follow the loads: during the spin-up, each centrifugal weight is its product of the body-frame angular
// velocity, and the root's six weights are the hub joint's reaction (System::joint_reaction, the wrench on the beam
// at the root's reference point) in body axes; the tip, where nothing acts, has zero weights.
TEST(GeometricStiffening, TheWeightsAreTheSpinAndTheJointReaction) {
  const fr::BodyModel model = model_of(Formulation::gcms, true);
  ASSERT_TRUE(model.prestress);
  fr::System system;
  const int b = system.add_body("beam", model, fr::BodyState{});
  const Eigen::VectorXd q0 = system.initial_coordinates();
  const fr::Marker root = fr::interface_marker(model, b, "beam", "root");
  system.add_joint(fr::make_joint("hub", fr::JointType::driven_revolute, root, fr::ground_marker(fr::marker_position(root, q0)),
                                  Eigen::Vector3d::UnitY(), q0, Eigen::VectorXd(), [](double t) { return 200.0 * t * t; }));
  system.set_gravity(Eigen::Vector3d(0, 0, -9.81));
  EXPECT_EQ(system.prestress_gap(b), "");
  fr::GeneralizedAlphaOptions options;
  options.step = 1e-4;
  fr::GeneralizedAlpha integrator(system, options);
  for (int k = 0; k < 500; ++k) integrator.step();  // to 0.05 s: Ω = 20 rad/s, Ω̇ = 400 rad/s²
  const Eigen::VectorXd& q = integrator.coordinates();
  const Eigen::VectorXd& lambda = integrator.multipliers();
  // The weights the last iteration used, at the converged state: set them again there to compare exactly.
  system.set_prestress(integrator.time(), q, integrator.velocities(), lambda);
  const Eigen::VectorXd& weights = system.prestress_weights(b);
  const fr::Prestress& prestress = *model.prestress;
  const Eigen::Matrix3d a = system.orientation(b, q);
  const Eigen::Vector3d omega = a.transpose() * system.angular_velocity(b, q, integrator.velocities());
  EXPECT_NEAR(omega.norm(), 20.0, 5.0);  // the hub's 20 rad/s and the mean-axis frame's own vibration about it
  const Eigen::Matrix3d spin = omega * omega.transpose();
  const double products[6] = {spin(0, 0), spin(1, 1), spin(2, 2), spin(0, 1), spin(0, 2), spin(1, 2)};
  for (int c = 0; c < 6; ++c) EXPECT_NEAR(weights(prestress.centrifugal[static_cast<std::size_t>(c)]), products[c], 1e-9 * 400.0);
  const fr::JointReaction reaction = system.joint_reaction(0, integrator.time(), q, lambda);
  const Eigen::Vector3d force = a.transpose() * reaction.force, moment = a.transpose() * reaction.moment;
  ASSERT_GT(force.norm(), 1.0);  // the centripetal force m Ω² r and the hub's torque
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(weights(prestress.interface_cases[0][static_cast<std::size_t>(c)]), force(c), 1e-9 * force.norm());
    EXPECT_NEAR(weights(prestress.interface_cases[0][static_cast<std::size_t>(c + 3)]), moment(c), 1e-9 * moment.norm());
    EXPECT_EQ(weights(prestress.interface_cases[1][static_cast<std::size_t>(c)]), 0.0);
  }
}

// fbsim: a body file with geometric stiffness is stiffened by default, geometric_stiffness: false turns it off, and
// asking for it from a file that has none, or on a rigid body, is one line naming the scene line.
TEST(GeometricStiffening, FbsimUsesItWhenTheFileHasIt) {
  const auto& dir = beam_folder();
  const std::string scene = R"(bodies:
  beam: {file: beam.fbh5, modes: 4}
joints:
  hub: {type: driven-revolute, body: beam, interface: root, to: ground, axis: [0, 1, 0], speed: 150, ramp: 0.5}
integrator: {type: generalized-alpha, rho_inf: 0.9, step: 1.0e-4, end: 0.6}
outputs:
  tip: {body: beam, interface: tip, quantities: [position]}
)";
  flexbody::test::write_text(dir / "spin.yaml", scene);
  const flexbody::test::CliRun on = flexbody::test::run_fbsim(dir, "spin.yaml -o spin_on --json");
  ASSERT_EQ(on.exit_code, 0) << on.err;
  EXPECT_NE(on.out.find(R"("geometric_stiffening":[{"body":"beam","cases":18,"covers_all_loads":true,"gap":""}])"),
            std::string::npos) << on.out;
  std::string off = scene;
  off.replace(off.find("modes: 4}"), 9, "modes: 4, geometric_stiffness: false}");
  flexbody::test::write_text(dir / "spin_off.yaml", off);
  const flexbody::test::CliRun linear = flexbody::test::run_fbsim(dir, "spin_off.yaml -o spin_off --json");
  EXPECT_EQ(linear.exit_code, 1);  // 150 rad/s is 1.4 ω₁: the linear model's spin limit stops it
  EXPECT_NE(linear.err.find("has no centrifugal stiffening"), std::string::npos) << linear.err;
  std::string rigid = scene;
  rigid.replace(rigid.find("modes: 4}"), 9, "modes: rigid, geometric_stiffness: true}");
  flexbody::test::write_text(dir / "spin_rigid.yaml", rigid);
  const flexbody::test::CliRun refused = flexbody::test::run_fbsim(dir, "spin_rigid.yaml -o spin_rigid");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("spin_rigid.yaml:2: body 'beam' geometric_stiffness: a rigid body has no deformation to "
                             "stiffen"), std::string::npos) << refused.err;
}
