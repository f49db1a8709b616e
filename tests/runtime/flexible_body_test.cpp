// A free-floating flexible beam (improved GCMS, preprocessed here with the preprocess library): started in one
// mode it oscillates at that mode's frequency, conserves linear and angular momentum, and with ρ∞ = 1 conserves
// energy; the time error is second order.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/interfaces.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/gcms_constants.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "flexbody/runtime/damping.hpp"
#include "flexbody/runtime/full_order.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"
#include "test_bodies.hpp"
#include "test_meshes.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>
#include <vector>
#include <numbers>

namespace fr = flexbody::runtime;
namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};

// A 0.5 x 0.05 x 0.05 m steel beam (10 x 2 x 2 cells), 4 free-free modes, as a body file would hold it.
const flexbody::format::BodyData& beam() {
  static const flexbody::format::BodyData body = [] {
    return flexbody::test::free_free_body(flexbody::test::assemble(flexbody::test::box_mesh(0.5, 0.05, 0.05, 10, 2, 2), kSteel),
                                          kSteel, 4);
  }();
  return body;
}

// η_m = Σ_f,d C(f, 3m + d) ξ̄_f[d].
double modal_coordinate(const fr::BodyModel& model, const Eigen::VectorXd& q, int mode) {
  const Eigen::Matrix3d a = fr::orientation_of(q);
  double eta = 0.0;
  for (Eigen::Index f = 0; f < model.field_count(); ++f)
    eta += model.mode_coefficients.block<1, 3>(f, 3 * mode).dot(a.transpose() * q.segment<3>(12 + 3 * f));
  return eta;
}

// The beam floating freely, undeformed except for amplitude `eta` of `mode`.
fr::System floating(const fr::BodyModel& model, int mode, double eta) {
  fr::BodyState state;
  state.xi.resize(3 * model.field_count());
  for (Eigen::Index f = 0; f < model.field_count(); ++f)
    state.xi.segment<3>(3 * f) = eta * model.mode_coefficients.block<1, 3>(f, 3 * mode).transpose();
  fr::System system;
  system.add_body("beam", model, state);
  return system;
}

struct Momenta {
  Eigen::Vector3d linear, angular;
};
// p = Σ_k G(0, k) v_k, L = Σ_kl G(k, l) q_k × v_l (the nodal sums Σ m_i r_i × ṙ_i through G).
Momenta momenta(const fr::BodyModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  const Eigen::MatrixXd& g = model.mass_matrix;
  Momenta out{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  for (Eigen::Index k = 0; k < g.rows(); ++k) {
    out.linear += g(0, k) * v.segment<3>(3 * k);
    for (Eigen::Index l = 0; l < g.cols(); ++l) out.angular += g(k, l) * q.segment<3>(3 * k).cross(v.segment<3>(3 * l));
  }
  return out;
}

}  // namespace

TEST(FlexibleBody, OscillatesAtItsModeFrequencyAndConservesMomentum) {
  const fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  for (int mode : {0, 2}) {
    SCOPED_TRACE(mode);
    const double f = model.frequencies_hz(mode), period = 1.0 / f;
    const double eta0 = 1e-3;  // kg^1/2 m: tip deflections of ~1e-4 m, small strain
    const fr::System system = floating(model, mode, eta0);
    fr::GeneralizedAlphaOptions options;
    options.rho_infinity = 1.0;
    options.step = period / 800;
    // The discrete equations conserve momentum exactly; Newton must then converge to round-off, not to the default
    // 1e-6 of each step's predictor-corrector distance (whose remainder, with a kept Newton matrix, shows up in the
    // momentum); 1e-14 leaves only the round-off floor to stop it.
    options.tolerance = 1e-14;
    fr::GeneralizedAlpha integrator(system, options);
    // Zero crossings of η(t) over 4 periods: 8 crossings, T = (last − first) / 3.5.
    std::vector<double> crossings;
    double previous = modal_coordinate(model, integrator.coordinates(), mode);
    double worst_momentum = 0.0;
    while (integrator.time() < 4.2 * period) {
      integrator.step();
      const double eta = modal_coordinate(model, integrator.coordinates(), mode);
      if ((eta > 0) != (previous > 0))
        crossings.push_back(integrator.time() - options.step * eta / (eta - previous));
      previous = eta;
      const Momenta p = momenta(model, integrator.coordinates(), integrator.velocities());
      worst_momentum = std::max({worst_momentum, p.linear.norm(), p.angular.norm()});
    }
    ASSERT_GE(crossings.size(), 8u);
    const double measured = (crossings.back() - crossings.front()) / (0.5 * static_cast<double>(crossings.size() - 1));
    // ρ∞ = 1 is the trapezoidal rule: period error (ω h)² / 12 = (2π/800)² / 12 = 5e-6; the GCMS frequency equals the
    // mode's exactly (the mode lies in the basis); interpolating the crossings linearly adds ~1e-6.
    EXPECT_NEAR(measured, period, 1e-4 * period);
    // Momentum starts at zero; scale: m |v| |r| with |v| ~ ω η0 / √m.
    const double scale = std::sqrt(model.mass) * 2 * std::numbers::pi * f * eta0 * 0.5;
    EXPECT_LT(worst_momentum, 1e-10 * scale);
  }
}

TEST(FlexibleBody, EnergyAndOrthogonalityHoldOverTenThousandSteps) {
  const fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  fr::BodyState state;
  state.angular_velocity = Eigen::Vector3d(0.0, 0.0, 2.0);  // a slow spin, well below the first mode
  state.xi = Eigen::VectorXd::Zero(3 * model.field_count());
  for (Eigen::Index f = 0; f < model.field_count(); ++f)
    state.xi.segment<3>(3 * f) = 1e-3 * model.mode_coefficients.block<1, 3>(f, 0).transpose();
  fr::System system;
  system.add_body("beam", model, state);
  fr::GeneralizedAlphaOptions options;
  options.rho_infinity = 1.0;
  options.step = 1.0 / model.frequencies_hz(0) / 100;
  fr::GeneralizedAlpha integrator(system, options);
  const double e0 = system.energies(integrator.coordinates(), integrator.velocities()).total();
  double worst_energy = 0.0, worst_orthogonality = 0.0;
  for (int i = 0; i < 10000; ++i) {
    integrator.step();
    const fr::Energies e = system.energies(integrator.coordinates(), integrator.velocities());
    worst_energy = std::max(worst_energy, std::abs(e.total() - e0) / e0);
    const Eigen::Matrix3d a = fr::orientation_of(integrator.coordinates());
    worst_orthogonality = std::max(worst_orthogonality, (a.transpose() * a - Eigen::Matrix3d::Identity()).norm());
  }
  EXPECT_LT(worst_energy, 1e-6);
  EXPECT_LT(worst_orthogonality, 1e-9);
}

TEST(FlexibleBody, HalvingTheStepDividesTheErrorByFour) {
  // η(t) = η0 cos ωt, compared at t = 1.25 T where η crosses zero: there the error is the phase error, which is
  // second order (at a maximum it would be its square, and the algorithmic damping is third order).
  const fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  const double period = 1.0 / model.frequencies_hz(0);
  auto eta_at_end = [&](int steps_per_period) {
    fr::GeneralizedAlphaOptions options;
    options.rho_infinity = 0.8;
    options.step = period / steps_per_period;
    const fr::System system = floating(model, 0, 1e-3);
    fr::GeneralizedAlpha integrator(system, options);
    for (int i = 0; i < steps_per_period * 5 / 4; ++i) integrator.step();
    return modal_coordinate(model, integrator.coordinates(), 0);
  };
  const double reference = eta_at_end(48 * 64);
  const double e1 = std::abs(eta_at_end(48) - reference), e2 = std::abs(eta_at_end(96) - reference),
               e3 = std::abs(eta_at_end(192) - reference);
  // Second order: ratios near 4 (3.5 to 4.5 allows for higher-order terms and the reference's own error, 1/4096
  // of e1).
  EXPECT_GT(e1 / e2, 3.5);
  EXPECT_LT(e1 / e2, 4.5);
  EXPECT_GT(e2 / e3, 3.5);
  EXPECT_LT(e2 / e3, 4.5);
}

namespace {

// A flexible pendulum: the beam pinned at a corner node about z, under gravity, released from horizontal, for 300
// steps of 0.2 ms. The final coordinates and the Newton iterations it took.
std::pair<Eigen::VectorXd, long> swing_pinned_beam(const fr::BodyModel& model, fr::NewtonMatrix matrix) {
  fr::System system;
  const int b = system.add_body("beam", model, fr::BodyState{});
  Eigen::Index corner = 0;
  model.nodes.col(0).minCoeff(&corner);
  const fr::Marker pin = fr::node_marker(model, b, "beam", corner);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  system.add_joint(fr::make_joint("pin", fr::JointType::revolute, pin, fr::ground_marker(fr::marker_position(pin, q0)),
                                  Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd()));
  system.set_gravity(Eigen::Vector3d(0, -9.81, 0));
  fr::GeneralizedAlphaOptions options;
  options.newton_matrix = matrix;
  options.step = 2e-4;
  fr::GeneralizedAlpha integrator(system, options);
  for (int i = 0; i < 300; ++i) integrator.step();
  return {Eigen::VectorXd(integrator.coordinates()), integrator.total_iterations()};
}

}  // namespace

TEST(FlexibleBody, ConstantCoreAndDenseNewtonGiveTheSameMotion) {
  // The constant-core elimination (C = G_ff ⊗ I3 + K̂/β' factorized once) solves the same Newton equations as the
  // dense matrix except for Â(G_ff ⊗ I3)Âᵀ vs G_ff ⊗ I3, equal while AᵀA = I (both keep their matrix across steps).
  const fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  const auto [dense, dense_iterations] = swing_pinned_beam(model, fr::NewtonMatrix::dense);
  const auto [core, core_iterations] = swing_pinned_beam(model, fr::NewtonMatrix::constant_core);
  // Both stop by the default Newton test (1e-6 of each step's predictor-corrector distance, which is ~1e-11 of the
  // beam's size here); over 300 steps the difference stays within 1e-8.
  EXPECT_LT((dense - core).cwiseAbs().maxCoeff(), 1e-8 * dense.cwiseAbs().maxCoeff());
  EXPECT_LE(core_iterations, dense_iterations * 21 / 20);  // the same convergence, within 5 %
}

TEST(FlexibleBody, TheShortMassProductGivesTheSameMotion) {
  // make_body_model makes G_ff = I exact for the file's orthonormal fields, and the mass products then skip the
  // n_f-square block. The same model with the flag cleared takes the general product: the pendulum must move the
  // same way, up to the Newton iteration's error over 300 steps.
  fr::BodyModel fast = fr::make_body_model(beam(), std::nullopt, "beam");
  ASSERT_TRUE(fast.unit_field_mass);
  fr::BodyModel general = fast;
  general.unit_field_mass = false;
  const Eigen::VectorXd q_fast = swing_pinned_beam(fast, fr::NewtonMatrix::constant_core).first;
  const Eigen::VectorXd q_general = swing_pinned_beam(general, fr::NewtonMatrix::constant_core).first;
  EXPECT_LT((q_fast - q_general).cwiseAbs().maxCoeff(), 1e-8 * q_general.cwiseAbs().maxCoeff());
}

// Issue 12, item 4: a flexible pendulum at the default settings (only the step given) converges at second order. The
// beam is pinned at a corner about z and released horizontal; the error is that of the far corner at t = 0.25 s
// against the same model at a quarter of the smallest step with a Newton tolerance 1e-3 of the default. Rayleigh
// damping β = 1e-5 s (ζ = 0.05 in the first mode, 1.6 kHz) overdamps the generalized basis' fields above 32 kHz
// (FORMULATION.md section 6), which the sudden release excites and no step here resolves: undamped, their response
// converges erratically (bench/README.md, "Convergence").
TEST(FlexibleBody, APendulumAtDefaultSettingsConvergesAtSecondOrder) {
  fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  model.damping = fr::rayleigh_damping(model, 0.0, 1e-5);
  Eigen::Index pinned = 0, far = 0;
  model.nodes.rowwise().sum().minCoeff(&pinned);
  model.nodes.rowwise().sum().maxCoeff(&far);
  auto far_corner_at_end = [&](const fr::GeneralizedAlphaOptions& options) {
    fr::System system;
    const int b = system.add_body("beam", model, fr::BodyState{});
    const fr::Marker pin = fr::node_marker(system.model(b), b, "beam", pinned);
    const Eigen::VectorXd q0 = system.initial_coordinates();
    system.add_joint(fr::make_joint("pin", fr::JointType::revolute, pin, fr::ground_marker(fr::marker_position(pin, q0)),
                                    Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd()));
    system.set_gravity(Eigen::Vector3d(0, -9.81, 0));
    fr::GeneralizedAlpha integrator(system, options);
    for (long i = 0; i < std::lround(0.25 / options.step); ++i) integrator.step();
    const fr::Marker corner = fr::node_marker(system.model(b), b, "beam", far);
    return Eigen::Vector3d(fr::marker_position(corner, system.body_coordinates(integrator.coordinates(), b)));
  };
  const std::vector<double> steps{4e-4, 2e-4, 1e-4, 5e-5};
  fr::GeneralizedAlphaOptions tight;
  tight.step = steps.back() / 4;
  tight.tolerance *= 1e-3;
  const Eigen::Vector3d reference = far_corner_at_end(tight);
  std::vector<double> errors;
  for (const double h : steps) {
    fr::GeneralizedAlphaOptions options;
    options.step = h;
    errors.push_back((far_corner_at_end(options) - reference).norm());
  }
  // Measured: 6.59e-7, 1.64e-7, 4.05e-8, 9.66e-9 m (ratios 4.02, 4.05, 4.19: the last is raised by the reference's
  // own error, 1/16 of the last). Second order: ratios of 4, within 3.6 to 4.4.
  for (std::size_t i = 1; i < errors.size(); ++i) {
    EXPECT_GT(errors[i - 1] / errors[i], 3.6) << "h = " << steps[i];
    EXPECT_LT(errors[i - 1] / errors[i], 4.4) << "h = " << steps[i];
  }
}

TEST(FlexibleBody, ModalAndRayleighDampingGiveTheirLogarithmicDecrement) {
  // Started in mode 1, the free beam decays like η0 e^(−ζωt) cos(ω_d t + ...): the peaks one damped period apart
  // shrink by the logarithmic decrement δ = 2πζ / √(1 − ζ²). ρ∞ = 1 adds no numerical damping; with 400 steps per
  // period the discrete decay rate is off by O((ωh)²) ~ 1e-4 relative, so δ is asserted to 1e-3.
  fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  const double omega = 2 * std::numbers::pi * model.frequencies_hz(0);
  Eigen::VectorXd ratios = Eigen::VectorXd::Zero(model.modes);
  ratios(0) = 0.02;
  for (const auto& [name, damping, zeta] :
       {std::tuple{"modal", fr::modal_damping(model, ratios), 0.02},
        std::tuple{"rayleigh", fr::rayleigh_damping(model, 0.0, 2 * 0.01 / omega), 0.01}}) {
    SCOPED_TRACE(name);
    model.damping = damping;
    const fr::System system = floating(model, 0, 1e-3);
    fr::GeneralizedAlphaOptions options;
    options.rho_infinity = 1.0;
    const double period = 2 * std::numbers::pi / omega;
    options.step = period / 400;
    fr::GeneralizedAlpha integrator(system, options);
    // The maximum of η within a quarter period of each damped period k T_d (sampled every T/400: the sampled
    // maximum is within 3e-5 of the true one, and the error cancels in the ratio).
    const double damped_period = period / std::sqrt(1 - zeta * zeta);
    std::vector<double> peaks(5, 0.0);
    while (integrator.time() < 4.3 * period) {
      integrator.step();
      const double t = integrator.time(), eta = modal_coordinate(model, integrator.coordinates(), 0);
      const auto k = static_cast<std::size_t>(std::lround(t / damped_period));
      if (k >= 1 && k <= 4 && std::abs(t - static_cast<double>(k) * damped_period) < 0.25 * period)
        peaks[k] = std::max(peaks[k], eta);
    }
    const double measured = std::log(peaks[1] / peaks[4]) / 3.0;
    const double expected = 2 * std::numbers::pi * zeta / std::sqrt(1 - zeta * zeta);
    EXPECT_NEAR(measured, expected, 1e-3 * expected);
  }
}

namespace {

// A slender steel beam 1 x 0.02 x 0.02 m (40 x 2 x 2 cells), 4 free-free modes, driven about z at one end node
// (the joint prescribes the body frame's angle). The speed is ramped smoothly (φ̇ = Ω (1 − cos πt/T) / 2) to Ω,
// given in units of the first free-free bending frequency ω_1, over T = 300 periods of ω_1: slowly enough that
// the angular acceleration's own load stays small.
struct SpinResult {
  bool failed = false;
  std::string message;
  double largest_rms = 0.0;
  bool finite = true;
  double speed_at_end = 0.0;  ///< Ω at the last completed step, in units of ω_1
  std::vector<std::string> warnings;
};
// The beam spun up to speed_over_first_mode ω_1; the spin checks at their defaults unless `spin_checks` is false,
// where the deformation limit alone watches (as before issue 12).
SpinResult spin_up(double speed_over_first_mode, bool spin_checks = false, double deformation_limit = 0.02,
                   double spin_limit = 0.5) {
  static const flexbody::format::BodyData body = [] {
    const auto model = flexbody::test::assemble(flexbody::test::box_mesh(1.0, 0.02, 0.02, 40, 2, 2), kSteel);
    flexbody::format::BodyData b;
    b.mass = fp::mass_properties(model.scalar_mass, model.mesh.nodes);
    b.mesh.nodes = model.mesh.nodes.rowwise() - b.mass.center_of_mass_input.transpose();
    fp::FreeFreeOptions options;
    options.modes = 4;
    const fp::FreeFreeModes modes = fp::free_free_modes(b.mesh.nodes, model.stiffness, model.scalar_mass, kSteel, options);
    b.modes.frequencies_hz = modes.frequencies_hz;
    b.modes.relative_residuals = modes.relative_residuals;
    b.modes.upsilon = fp::upsilon_from_modes(modes.vectors);
    b.gcms = fp::gcms_constants(model.stiffness, model.scalar_mass, b.mesh.nodes, b.modes.upsilon);
    return b;
  }();
  const fr::BodyModel model = fr::make_body_model(body, std::nullopt, "slender beam");
  const double omega_1 = 2 * std::numbers::pi * model.frequencies_hz(0);
  const double speed = speed_over_first_mode * omega_1, ramp = 300.0 * 2 * std::numbers::pi / omega_1;
  fr::System system;
  const int b = system.add_body("beam", model, fr::BodyState{});
  Eigen::Index hub = 0;
  (model.nodes.rowwise() - model.nodes.colwise().minCoeff()).rowwise().norm().minCoeff(&hub);
  const fr::Marker m = fr::node_marker(model, b, "beam", hub);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  system.add_joint(fr::make_joint("hub", fr::JointType::driven_revolute, m, fr::ground_marker(fr::marker_position(m, q0)),
                                  Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd(), [speed, ramp](double t) {
                                    if (t >= ramp) return speed * (t - 0.5 * ramp);
                                    return 0.5 * speed * (t - ramp / std::numbers::pi * std::sin(std::numbers::pi * t / ramp));
                                  }));
  fr::GeneralizedAlphaOptions options;
  options.rho_infinity = 0.8;
  options.step = 2 * std::numbers::pi / omega_1 / 40;
  options.deformation_limit = deformation_limit;
  options.spin_limit = spin_limit;
  if (!spin_checks) options.spin_warning = options.spin_limit = 0.0;
  fr::GeneralizedAlpha integrator(system, options);
  SpinResult result;
  try {
    while (integrator.time() < 1.5 * ramp) {
      integrator.step();
      const Eigen::VectorXd xi = integrator.coordinates().tail(3 * model.field_count());
      result.largest_rms = std::max(result.largest_rms, xi.norm() / std::sqrt(model.mass));
    }
  } catch (const fr::StepFailure& e) {
    result.failed = true;
    result.message = e.what();
  }
  result.finite = integrator.coordinates().allFinite();
  result.warnings = integrator.warnings();
  const double t = std::min(integrator.time(), ramp);
  result.speed_at_end = speed_over_first_mode * 0.5 * (1 - std::cos(std::numbers::pi * t / ramp));
  return result;
}

}  // namespace

TEST(FlexibleBody, SpinUpBeyondTheFirstBendingFrequencyIsReported) {
  // At a fifth of the first bending frequency the spinning beam stays in the small-deformation range.
  const SpinResult slow = spin_up(0.2);
  EXPECT_FALSE(slow.failed) << slow.message;
  EXPECT_LT(slow.largest_rms, 0.005);
  // Beyond it a linear corotational model has no centrifugal stiffening (FORMULATION.md section 8): the
  // deformation grows without bound. The run must stop with that diagnosis, its state finite, never NaN.
  const SpinResult fast = spin_up(1.5);
  ASSERT_TRUE(fast.failed) << "largest RMS displacement " << fast.largest_rms << " m";
  EXPECT_NE(fast.message.find("body 'beam' left the small-deformation range of its linear model"), std::string::npos)
      << fast.message;
  EXPECT_TRUE(fast.finite);
  // The in-plane bending stiffness softens like ω² − Ω² (centrifugal softening without the stiffening of the
  // axial tension); with the hub's constraint the RMS deformation reaches the 2 % limit at Ω ≈ 0.39 ω_1
  // (measured), well past the slow case and before the target speed.
  EXPECT_GT(fast.speed_at_end, 0.25);
  EXPECT_LT(fast.speed_at_end, 1.5);
}

// Issue 12, item 7: the loss of validity is detected from its cause, the spin against the body's lowest elastic
// frequency ω₁ (here the free-free first mode), without waiting for a large deformation: with the deformation
// limit off, the run warns once at Ω = 0.25 ω₁ and stops at the spin limit, naming the spin and the model's error.
// On 521de58 nothing watched the spin (the clamped beam ran to 1.5 ω₁ with exit 0, 43 % off at the peak).
// The limit here is 0.4, not the default 0.5: held at one end this beam's lowest frequency is a sixth of the
// free-free ω₁, and its linear model diverges at Ω ≈ 0.48 ω₁ (measured: RMS deformation 0.12 m at 0.445 ω₁,
// 4 m at 0.48 ω₁), where either the spin limit or Newton's failure came first, by chance.
TEST(FlexibleBody, ASpinAboveTheLimitIsRefused) {
  const SpinResult slow = spin_up(0.2, true, 0.0, 0.4);
  EXPECT_FALSE(slow.failed) << slow.message;
  EXPECT_TRUE(slow.warnings.empty());
  const SpinResult fast = spin_up(1.5, true, 0.0, 0.4);
  ASSERT_TRUE(fast.failed);
  EXPECT_NE(fast.message.find("body 'beam' spins at"), std::string::npos) << fast.message;
  EXPECT_NE(fast.message.find("has no centrifugal stiffening"), std::string::npos) << fast.message;
  EXPECT_NE(fast.message.find("(limit: 0.4 of it)"), std::string::npos) << fast.message;
  EXPECT_TRUE(fast.finite);
  // The last completed step is just below the limit (a step changes Ω by ~1e-3 ω₁ on this ramp).
  EXPECT_NEAR(fast.speed_at_end, 0.4, 0.01);
  ASSERT_EQ(fast.warnings.size(), 1u);
  EXPECT_NE(fast.warnings[0].find("(warning above 0.25 of it)"), std::string::npos) << fast.warnings[0];
}

TEST(FlexibleBody, AVeryStiffBarPendulumHasTheRigidPeriod) {
  // The rigid limit: the beam of the other tests with E raised 10⁴-fold (deflections ~1e-9 of its length), pinned
  // on its axis at one end and released from horizontal. Its half period is the exact large-amplitude one of the
  // rigid physical pendulum, T = 4 √(I_p/(m g d)) K(sin 45°), with m, d and I_p from the body's G.
  const fp::Material stiff{"stiff steel", 210e13, 0.3, 7850.0};
  const auto fe = flexbody::test::assemble(flexbody::test::box_mesh(0.5, 0.05, 0.05, 10, 2, 2), stiff);
  flexbody::format::BodyData body;
  body.mass = fp::mass_properties(fe.scalar_mass, fe.mesh.nodes);
  body.mesh.nodes = fe.mesh.nodes.rowwise() - body.mass.center_of_mass_input.transpose();
  fp::FreeFreeOptions options;
  options.modes = 4;
  const fp::FreeFreeModes modes = fp::free_free_modes(body.mesh.nodes, fe.stiffness, fe.scalar_mass, stiff, options);
  body.modes.frequencies_hz = modes.frequencies_hz;
  body.modes.relative_residuals = modes.relative_residuals;
  body.modes.upsilon = fp::upsilon_from_modes(modes.vectors);
  body.gcms = fp::gcms_constants(fe.stiffness, fe.scalar_mass, body.mesh.nodes, body.modes.upsilon);
  const fr::BodyModel model = fr::make_body_model(body, std::nullopt, "stiff beam");

  fr::System system;
  const int b = system.add_body("beam", model, fr::BodyState{});
  Eigen::Index pivot = 0;  // the node on the axis of the end face x = 0
  (model.nodes.rowwise() - Eigen::RowVector3d(model.nodes.col(0).minCoeff(), 0, 0)).rowwise().norm().minCoeff(&pivot);
  const fr::Marker pin = fr::node_marker(model, b, "beam", pivot);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  system.add_joint(fr::make_joint("pin", fr::JointType::revolute, pin, fr::ground_marker(fr::marker_position(pin, q0)),
                                  Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd()));
  const double g = 9.81;
  system.set_gravity(Eigen::Vector3d(0, -g, 0));

  const Eigen::Vector3d p = model.nodes.row(pivot).transpose();
  const Eigen::Matrix3d j = model.mass_matrix.block<3, 3>(1, 1);
  const double izz = j(0, 0) + j(1, 1) + p.head<2>().squaredNorm() * model.mass;  // (tr J − J_zz) + m d²
  const double d = p.head<2>().norm();
  double a = 1.0, b_agm = std::sqrt(0.5);  // K(sin 45°) = π / (2 AGM(1, cos 45°))
  for (int i = 0; i < 30; ++i) {
    const double next = 0.5 * (a + b_agm);
    b_agm = std::sqrt(a * b_agm);
    a = next;
  }
  const double period = 4.0 * std::sqrt(izz / (model.mass * g * d)) * std::numbers::pi / (2.0 * a);

  fr::GeneralizedAlphaOptions integration;
  integration.rho_infinity = 0.9;
  integration.step = 2e-4;
  fr::GeneralizedAlpha integrator(system, integration);
  double previous_rate = 0.0, previous_t = 0.0, turning = 0.0;
  while (integrator.time() < 0.8 * period) {
    integrator.step();
    const Eigen::Matrix3d a_now = fr::orientation_of(integrator.coordinates());
    const double rate = (fr::orientation_of(integrator.velocities()) * a_now.transpose())(1, 0);
    const double t = integrator.time();
    if (t > 0.25 * period && previous_rate != 0.0 && (rate > 0) != (previous_rate > 0)) {
      turning = previous_t + (t - previous_t) * previous_rate / (previous_rate - rate);
      break;
    }
    previous_rate = rate;
    previous_t = t;
  }
  ASSERT_GT(turning, 0.0);
  // Second order with ω h ~ 1e-3 (period error ~1e-7) and the turning point interpolated linearly: 1e-4 is the
  // issue's bar, and the stiff body's own elasticity changes the period by ~1e-9.
  EXPECT_NEAR(2.0 * turning, period, 1e-4 * period);
}

TEST(FlexibleBody, ClampedBeamUnderGravityConvergesToTheFullOrderSolution) {
  // The beam clamped at x = 0 with gravity switched on at t = 0: its tip deflection over 8 ms (1.3 periods of the
  // first cantilever mode) by the improved GCMS with a Craig-Bampton basis (rbe2 root, fixed joint) of 1, 2, 4 and
  // 8 fixed-interface modes, against the unreduced improved ACF of the same mesh (every root node held by a
  // spherical joint). The error must fall as modes are added and be small with 8.
  const auto fe = flexbody::test::assemble(flexbody::test::box_mesh(0.5, 0.05, 0.05, 10, 2, 2), kSteel);
  const flexbody::format::MassProperties mass = fp::mass_properties(fe.scalar_mass, fe.mesh.nodes);
  const fp::RowMatrixX3d nodes = fe.mesh.nodes.rowwise() - mass.center_of_mass_input.transpose();
  std::vector<int> root;
  for (Eigen::Index i = 0; i < nodes.rows(); ++i)
    if (fe.mesh.nodes(i, 0) == 0.0) root.push_back(static_cast<int>(i));
  Eigen::Index tip = 0;
  (fe.mesh.nodes.rowwise() - Eigen::RowVector3d(0.5, 0.025, 0.025)).rowwise().norm().minCoeff(&tip);
  const Eigen::Vector3d g(0, -9.81, 0);
  const double end = 8e-3, step = 2e-5;

  auto tip_history = [&](fr::System& system, int body, const fr::Marker& tip_marker) {
    system.set_gravity(g);
    fr::GeneralizedAlphaOptions options;
    options.rho_infinity = 0.8;
    options.step = step;
    fr::GeneralizedAlpha integrator(system, options);
    std::vector<double> y;
    while (integrator.time() < end - 0.5 * step) {
      integrator.step();
      y.push_back(fr::marker_position(tip_marker, system.body_coordinates(integrator.coordinates(), body)).y());
    }
    return y;
  };

  // The full-order reference.
  std::vector<double> reference;
  {
    const fr::BodyModel model = fr::full_order_model(fp::full_from_upper(fe.stiffness), fp::full_from_upper(fe.scalar_mass),
                                                     nodes);
    fr::System system;
    const int b = system.add_body("beam", model, fr::BodyState{});
    const Eigen::VectorXd q0 = system.initial_coordinates();
    for (int i : root) {
      const fr::Marker m = fr::node_marker(model, b, "beam", i);
      system.add_joint(fr::make_joint("root " + std::to_string(i), fr::JointType::spherical, m,
                                      fr::ground_marker(fr::marker_position(m, q0)), Eigen::Vector3d::UnitZ(), q0,
                                      Eigen::VectorXd()));
    }
    reference = tip_history(system, b, fr::node_marker(model, b, "beam", tip));
  }
  const double y0 = nodes(tip, 1);
  double largest = 0.0;
  for (double y : reference) largest = std::max(largest, std::abs(y - y0));
  ASSERT_GT(largest, 1e-7);  // the tip moves (about 5e-6 m here)

  std::vector<double> errors;
  for (int fixed_modes : {1, 2, 4, 8}) {
    fp::RigidInterface clamp;
    clamp.nodes = Eigen::Map<const Eigen::VectorXi>(root.data(), static_cast<Eigen::Index>(root.size()));
    clamp.reference_point = Eigen::Vector3d::Zero();
    for (int i : root) clamp.reference_point += nodes.row(i).transpose() / static_cast<double>(root.size());
    fp::CraigBamptonOptions options;
    options.fixed_interface_modes = fixed_modes;
    const fp::CraigBamptonModes cb = fp::craig_bampton_modes(nodes, fe.stiffness, fe.scalar_mass, kSteel, {clamp}, options);
    flexbody::format::BodyData body;
    body.mass = mass;
    body.mesh.nodes = nodes;
    body.modes.frequencies_hz = cb.frequencies_hz;
    body.modes.upsilon = fp::upsilon_from_modes(cb.vectors);
    body.gcms = fp::gcms_constants(fe.stiffness, fe.scalar_mass, nodes, body.modes.upsilon);
    fp::SurfacePatch patch{clamp.nodes, Eigen::VectorXd::Constant(clamp.nodes.size(), 1.0 / static_cast<double>(clamp.nodes.size()))};
    body.interfaces.push_back(fp::interface_marker("root", "rbe2", patch, nodes, body.gcms.fields));
    const fr::BodyModel model = fr::make_body_model(body, std::nullopt, "cb beam");
    fr::System system;
    const int b = system.add_body("beam", model, fr::BodyState{});
    // The clamp: three non-collinear root nodes held by spherical joints. In a Craig-Bampton basis every field is
    // affine on the root patch, so this holds the whole patch, like the reference's joint at every root node; a
    // fixed joint at the rbe2 marker alone would hold only its mean position and rotation, and the generalized
    // coordinates (ξ_f, not modal amplitudes) could still stretch the patch.
    const Eigen::VectorXd q0 = system.initial_coordinates();
    for (const Eigen::RowVector3d& corner : {Eigen::RowVector3d(0, 0, 0), Eigen::RowVector3d(0, 0.05, 0), Eigen::RowVector3d(0, 0, 0.05)}) {
      Eigen::Index i = 0;
      (fe.mesh.nodes.rowwise() - corner).rowwise().norm().minCoeff(&i);
      const fr::Marker m = fr::node_marker(model, b, "beam", i);
      system.add_joint(fr::make_joint("clamp " + std::to_string(i), fr::JointType::spherical, m,
                                      fr::ground_marker(fr::marker_position(m, q0)), Eigen::Vector3d::UnitZ(), q0,
                                      Eigen::VectorXd()));
    }
    const std::vector<double> y = tip_history(system, b, fr::node_marker(model, b, "beam", tip));
    double error = 0.0;
    for (std::size_t k = 0; k < y.size(); ++k) error = std::max(error, std::abs(y[k] - reference[k]));
    errors.push_back(error / largest);
  }
  // Measured: 0.44, 0.015, 0.0014, 0.00027 of the largest deflection for 1, 2, 4, 8 modes. Each step down must hold,
  // and 8 modes must be within 1e-3.
  for (std::size_t k = 1; k < errors.size(); ++k) EXPECT_LT(errors[k], errors[k - 1]) << k;
  EXPECT_LT(errors[3], 1e-3);
}

TEST(FullOrderBody, OscillatesAtTheFiniteElementFrequency) {
  // The unreduced improved ACF (sparse K̄ and M_s) of the 10 x 2 x 2 beam, floating freely, started in the first
  // free-free mode of the same finite-element matrices as computed by fbprep's eigensolver (ARPACK): it must swing
  // at that mode's frequency. Independent of every reduction: the mode is not in any basis here, only in the
  // initial state, and the full-order dynamics must keep it.
  const auto fe = flexbody::test::assemble(flexbody::test::box_mesh(0.5, 0.05, 0.05, 10, 2, 2), kSteel);
  const flexbody::format::MassProperties mass = fp::mass_properties(fe.scalar_mass, fe.mesh.nodes);
  const fp::RowMatrixX3d nodes = fe.mesh.nodes.rowwise() - mass.center_of_mass_input.transpose();
  fp::FreeFreeOptions options;
  options.modes = 1;
  const fp::FreeFreeModes modes = fp::free_free_modes(nodes, fe.stiffness, fe.scalar_mass, kSteel, options);
  const Eigen::SparseMatrix<double> m_s = fp::full_from_upper(fe.scalar_mass);
  const fr::BodyModel model = fr::full_order_model(fp::full_from_upper(fe.stiffness), m_s, nodes);
  EXPECT_TRUE(model.needs_translational_tisserand());
  const Eigen::VectorXd phi = modes.vectors.col(0);  // M̄-normalised [kg^-1/2], node-interleaved
  const double eta0 = 1e-3, period = 1.0 / modes.frequencies_hz(0);
  fr::BodyState state;
  state.xi = eta0 * phi;  // A = I: ξ = ξ̄ are the nodal displacements
  fr::System system;
  system.add_body("beam", model, state);
  // η = φᵀ (M_s ⊗ I3) ξ̄, the mode's amplitude in the body frame.
  auto amplitude = [&](const Eigen::VectorXd& q) {
    const Eigen::Matrix3d a = fr::orientation_of(q);
    Eigen::VectorXd xi_bar = fr::body_frame_coordinates(a, q.tail(q.size() - 12)), m_xi(xi_bar.size());
    for (int d = 0; d < 3; ++d) {
      const Eigen::VectorXd x_d = Eigen::Map<const Eigen::VectorXd, 0, Eigen::InnerStride<3>>(xi_bar.data() + d, nodes.rows());
      Eigen::Map<Eigen::VectorXd, 0, Eigen::InnerStride<3>>(m_xi.data() + d, nodes.rows()) = m_s * x_d;
    }
    return phi.dot(m_xi);
  };
  fr::GeneralizedAlphaOptions integration;
  integration.rho_infinity = 1.0;
  integration.step = period / 800;
  fr::GeneralizedAlpha integrator(system, integration);
  EXPECT_NEAR(amplitude(integrator.coordinates()), eta0, 1e-9 * eta0);
  std::vector<double> crossings;
  double previous = amplitude(integrator.coordinates());
  while (integrator.time() < 2.2 * period) {
    integrator.step();
    const double eta = amplitude(integrator.coordinates());
    if ((eta > 0) != (previous > 0)) crossings.push_back(integrator.time() - integration.step * eta / (eta - previous));
    previous = eta;
  }
  ASSERT_GE(crossings.size(), 4u);
  const double measured = (crossings.back() - crossings.front()) / (0.5 * static_cast<double>(crossings.size() - 1));
  // As for the reduced body: the trapezoidal rule lengthens the period by (ω h)² / 12 = 5.14e-6, which is what is
  // measured (5.14e-6); the crossings' interpolation adds ~1e-7.
  EXPECT_NEAR(measured, period, 1e-4 * period);
}

TEST(FullOrderBody, SparseAndDenseMassMatricesAgree) {
  // The sparse mass paths (KKT assembly, mass products) against the dense G ⊗ I3, for a system holding a body-file
  // body and a full-order body: the same numbers.
  const auto fe = flexbody::test::assemble(flexbody::test::box_mesh(0.5, 0.05, 0.05, 10, 2, 2), kSteel);
  const flexbody::format::MassProperties mass = fp::mass_properties(fe.scalar_mass, fe.mesh.nodes);
  const fp::RowMatrixX3d nodes = fe.mesh.nodes.rowwise() - mass.center_of_mass_input.transpose();
  fr::System system;
  system.add_body("reduced", fr::make_body_model(beam(), std::nullopt, "beam"), fr::BodyState{});
  system.add_body("full", fr::full_order_model(fp::full_from_upper(fe.stiffness), fp::full_from_upper(fe.scalar_mass), nodes),
                  fr::BodyState{});
  const Eigen::MatrixXd dense = system.mass_matrix(system.initial_coordinates());
  EXPECT_EQ((Eigen::MatrixXd(system.sparse_mass_matrix(system.initial_coordinates())) - dense).norm(), 0.0);
  EXPECT_LT((dense - dense.transpose()).norm(), 1e-15 * dense.norm());  // the body file's G: symmetric to round-off
  std::srand(3);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(system.coordinate_count());
  EXPECT_LT((system.mass_product(system.initial_coordinates(), x) - dense * x).norm(), 1e-13 * (dense * x).norm());
  // An upper triangle alone (as the assembly stores it) is refused, not silently used.
  EXPECT_THROW(static_cast<void>(fr::full_order_model(Eigen::SparseMatrix<double>(fe.stiffness),
                                                      fp::full_from_upper(fe.scalar_mass), nodes)),
               std::invalid_argument);
}

TEST(JointReaction, MomentumBalanceOfAFlexibleBodyOnAFixedJoint) {
  // The 4-mode beam held at one end node by a fixed joint, vibrating under gravity. The joint's wrench closes the
  // body's balance exactly: m τ̈ = m g + F (τ is the centre of mass: G[0, 1:] = 0), and the rate of its angular
  // momentum about the origin, Σ_kl G_kl q_k × q̈_l, equals the moments of gravity (τ × m g) and of the joint
  // (p × F + M). The elastic and reference forces have no net moment (U and Φ are invariant under a rigid rotation),
  // so this tests the joint's moment with its ξ terms.
  const fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  fr::System system;
  const int b = system.add_body("beam", model, fr::BodyState{});
  Eigen::Index end = 0;
  model.nodes.col(0).minCoeff(&end);
  const fr::Marker m = fr::node_marker(model, b, "beam", end);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  system.add_joint(fr::make_joint("clamp", fr::JointType::fixed, m, fr::ground_marker(fr::marker_position(m, q0)),
                                  Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd()));
  const Eigen::Vector3d g(0, -9.81, 0);
  system.set_gravity(g);
  fr::GeneralizedAlphaOptions options;
  options.step = 2e-5;
  options.rho_infinity = 0.8;
  options.tolerance = 1e-14;  // the balance holds to the Newton tolerance: converge to round-off
  fr::GeneralizedAlpha integrator(system, options);
  for (int k = 0; k < 200; ++k) integrator.step();
  const Eigen::VectorXd& q = integrator.coordinates();
  const Eigen::VectorXd& qdd = integrator.accelerations();
  const fr::JointReaction r = system.joint_reaction(0, integrator.time(), q, integrator.multipliers());
  const double weight = model.mass * g.norm();
  EXPECT_LT((model.mass * qdd.head<3>() - model.mass * g - r.force).norm(), 1e-9 * weight);
  const Eigen::MatrixXd& gm = model.mass_matrix;
  Eigen::Vector3d rate = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < gm.rows(); ++k)
    for (Eigen::Index l = 0; l < gm.cols(); ++l) rate += gm(k, l) * q.segment<3>(3 * k).cross(qdd.segment<3>(3 * l));
  const Eigen::Vector3d p = fr::marker_position(m, q);
  const Eigen::Vector3d moments = q.head<3>().cross(model.mass * g) + p.cross(r.force) + r.moment;
  const double scale = weight * 0.5;  // N m: the weight at the beam's length
  EXPECT_GT(r.moment.norm(), 0.1 * scale);  // the clamp carries the beam's weight as a moment
  EXPECT_LT((rate - moments).norm(), 1e-9 * scale);
}
// Issue 12, item 8: a step whose Newton iteration fails is diagnosed from the last converged state, not from the
// failed iterate. On 521de58 this free beam spun at 500 rad/s with h = 1 ms (half a radian per step) stopped in its
// first step with "left the small-deformation range ... RMS elastic displacement 7745.63 m": the deformation of an
// iterate that Newton had not brought back, while the body was undeformed.
TEST(FlexibleBody, AFailedStepIsDiagnosedFromTheLastConvergedState) {
  const fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  fr::System system;
  fr::BodyState state;
  state.angular_velocity = Eigen::Vector3d(0, 0, 500.0);
  system.add_body("beam", model, state);
  fr::GeneralizedAlphaOptions options;
  options.step = 1e-3;
  fr::GeneralizedAlpha integrator(system, options);
  try {
    integrator.step();
    FAIL() << "the step converged; the test needs one that does not";
  } catch (const fr::StepFailure& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find("small-deformation range"), std::string::npos) << message;
    // 0.5 rad per step: the iteration diverges, to a non-finite correction or past the iteration limit.
    EXPECT_TRUE(message.find("did not converge") != std::string::npos ||
                message.find("the Newton iteration diverged") != std::string::npos) << message;
    EXPECT_NE(message.find("at the last converged step, t = 0 s"), std::string::npos) << message;
    EXPECT_NE(message.find("turned 0.5 rad per step (more than 0.1 rad per step: try a smaller step)"), std::string::npos)
        << message;
    EXPECT_NE(message.find("displacement of 0 m = 0 % of its size"), std::string::npos) << message;
  }
  EXPECT_EQ(integrator.time(), 0.0);  // the state stays at the last good step
}

// The velocity constraints of the stabilised index-2 form, Φ_q v, without forming Φ_q: the same numbers as the
// Jacobian's product, for reference rows and joints on flexible bodies, at a state off the constraint manifold.
TEST(System, ConstraintJacobianProductEqualsTheJacobianTimesTheVelocity) {
  const fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  fr::System system;
  fr::BodyState second;
  second.position = Eigen::Vector3d(0.5, 0, 0);
  const int b0 = system.add_body("left", model, fr::BodyState{}), b1 = system.add_body("right", model, second);
  Eigen::Index low = 0, high = 0;
  model.nodes.col(0).minCoeff(&low);
  model.nodes.col(0).maxCoeff(&high);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  const fr::Marker pin = fr::node_marker(model, b0, "left", low), tip = fr::node_marker(model, b0, "left", high);
  const fr::Marker root = fr::node_marker(model, b1, "right", low);
  system.add_joint(fr::make_joint("pin", fr::JointType::driven_revolute, pin,
                                  fr::ground_marker(fr::marker_position(pin, system.body_coordinates(q0, b0))),
                                  Eigen::Vector3d::UnitZ(), system.body_coordinates(q0, b0), Eigen::VectorXd(),
                                  [](double t) { return 0.3 * t * t; }));
  system.add_joint(fr::make_joint("link", fr::JointType::revolute, tip, root, Eigen::Vector3d::UnitY(),
                                  system.body_coordinates(q0, b0), system.body_coordinates(q0, b1)));
  std::srand(5);
  const Eigen::VectorXd q = q0 + 1e-2 * Eigen::VectorXd::Random(q0.size());
  const Eigen::VectorXd v = Eigen::VectorXd::Random(q0.size());
  const Eigen::VectorXd expected = system.constraint_jacobian(0.7, q) * v;
  const Eigen::VectorXd product = system.constraint_jacobian_product(0.7, q, v);
  ASSERT_EQ(product.size(), expected.size());
  // The same sums in another order: round-off of the terms, ~1e-16 |J| |v|.
  const double terms = (system.constraint_jacobian(0.7, q).cwiseAbs() * v.cwiseAbs()).maxCoeff();
  EXPECT_LT((product - expected).cwiseAbs().maxCoeff(), 1e-14 * terms);
}

// Review of 77a5e2a: the stopping test measured |δ + W Φ_qᵀ Δν|, whose parts cancelled, and the position correction
// reached the dynamic rows one iteration late, so Newton stopped before the velocities had converged: 6.5e-7 m/s
// off (|v| ≈ 3 m/s) on this pendulum against a dense, fresh, tight run, and the result depended on how old the
// kept Newton matrix was. Measured now, on the centre of mass's velocity (up to 1.44 m/s) over 2000 steps of 1e-4 s:
// 1.05e-8 m/s with the kept matrix, 3.3e-10 m/s rebuilt every iteration (the default tolerance, 1e-6 of the step's
// predictor-corrector distance, and γ'/β' = γ h: an iteration error of 1e-6 × 2e-7 m gives ~1e-8 m/s).
TEST(FlexibleBody, TheKeptNewtonMatrixGivesTheConvergedVelocities) {
  const fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  auto run = [&](fr::NewtonMatrix matrix, bool reuse, double tolerance) {
    fr::System system;
    const int b = system.add_body("beam", model, fr::BodyState{});
    Eigen::Index corner = 0;
    model.nodes.col(0).minCoeff(&corner);
    const fr::Marker pin = fr::node_marker(model, b, "beam", corner);
    const Eigen::VectorXd q0 = system.initial_coordinates();
    system.add_joint(fr::make_joint("pin", fr::JointType::revolute, pin, fr::ground_marker(fr::marker_position(pin, q0)),
                                    Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd()));
    system.set_gravity(Eigen::Vector3d(0, -9.81, 0));
    fr::GeneralizedAlphaOptions options;
    options.newton_matrix = matrix;
    options.reuse_newton_matrix = reuse;
    options.tolerance = tolerance;
    options.step = 1e-4;
    fr::GeneralizedAlpha integrator(system, options);
    std::vector<Eigen::VectorXd> velocities;
    for (int i = 0; i < 2000; ++i) {
      integrator.step();
      velocities.push_back(integrator.velocities().head<3>());
    }
    return velocities;
  };
  const auto reference = run(fr::NewtonMatrix::dense, false, 1e-14);
  const auto kept = run(fr::NewtonMatrix::constant_core, true, 1e-6);
  const auto fresh = run(fr::NewtonMatrix::constant_core, false, 1e-6);
  double kept_error = 0.0, fresh_error = 0.0, speed = 0.0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    kept_error = std::max(kept_error, (kept[i] - reference[i]).norm());
    fresh_error = std::max(fresh_error, (fresh[i] - reference[i]).norm());
    speed = std::max(speed, reference[i].norm());
  }
  ASSERT_GT(speed, 1.0);
  EXPECT_LT(kept_error, 5e-8);
  EXPECT_LT(fresh_error, 5e-9);
}
