// Issue 12, item 5: fast spins at ρ∞ = 1. The index-3 form (positions only) is weakly unstable there: the velocities
// drift off the hidden constraints of the orthogonality rows and a spinning body gains energy until Newton fails.
// The stabilised index-2 form, the default (ConstraintForm::stabilized_index2), keeps the invariants of a heavy top,
// a flipping plate and a spinning flexible beam; each test also runs the index-3 form to show that the scene is a
// hard one (on 521de58, the index-3 form was the only one).
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"

#include "test_bodies.hpp"
#include "test_meshes.hpp"


#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace fr = flexbody::runtime;
namespace fp = flexbody::preprocess;

namespace {

// A rigid body of mass m and second moment J = ∫ x xᵀ dm about its centre of mass.
fr::BodyModel rigid(double mass, const Eigen::Matrix3d& second_moment) {
  return fr::rigid_body_model(mass, second_moment, "rigid");
}

// L about the origin, Σ_kl G_kl q_k × v_l over the 3-blocks of q = [τ; a_1..3; ξ] (the nodal sums Σ m_i r_i × ṙ_i).
Eigen::Vector3d angular_momentum(const fr::BodyModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < model.mass_matrix.rows(); ++k)
    for (Eigen::Index j = 0; j < model.mass_matrix.cols(); ++j)
      l += model.mass_matrix(k, j) * q.segment<3>(3 * k).cross(v.segment<3>(3 * j));
  return l;
}

Eigen::Vector3d angular_velocity(const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  const Eigen::Matrix3d w = fr::orientation_of(v) * fr::orientation_of(q).transpose();  // [ω]×
  return 0.5 * Eigen::Vector3d(w(2, 1) - w(1, 2), w(0, 2) - w(2, 0), w(1, 0) - w(0, 1));
}

// The heavy top of bench/convergence_bench: a steel cylinder (r = 0.05 m, h = 0.2 m) on a spherical joint at the
// centre of its base, its axis 30° from the vertical, spinning at 150 rad/s about it.
struct HeavyTop {
  static constexpr double kRadius = 0.05, kHeight = 0.2, kSpin = 150.0;
  double mass = 7850.0 * std::numbers::pi * kRadius * kRadius * kHeight;
  fr::BodyModel model;
  fr::System system;
  HeavyTop() {
    const double r = kRadius, h = kHeight;
    model = rigid(mass, mass * Eigen::Vector3d(r * r / 4, r * r / 4, h * h / 12).asDiagonal());
    fr::BodyState state;
    state.orientation = Eigen::AngleAxisd(std::numbers::pi / 6, Eigen::Vector3d::UnitX()).toRotationMatrix();
    state.position = state.orientation * Eigen::Vector3d(0, 0, h / 2);
    state.angular_velocity = state.orientation * Eigen::Vector3d(0, 0, kSpin);
    const int top = system.add_body("top", model, state);
    const fr::Marker tip = fr::point_marker(model, top, "top", Eigen::Vector3d(0, 0, -h / 2));
    system.add_joint(fr::make_joint("tip", fr::JointType::spherical, tip, fr::ground_marker(Eigen::Vector3d::Zero()),
                                    Eigen::Vector3d::UnitZ(), system.initial_coordinates(), Eigen::VectorXd()));
    system.set_gravity(Eigen::Vector3d(0, 0, -9.81));
  }
};

struct Drift {
  double energy = 0.0, momentum = 0.0, spin = 0.0;  ///< the largest relative changes over the run
  bool failed = false;
};

Drift run_top(fr::ConstraintForm form, double step = 1e-4) {
  HeavyTop top;
  fr::GeneralizedAlphaOptions options;
  options.rho_infinity = 1.0;
  options.step = step;
  options.constraints = form;
  fr::GeneralizedAlpha integrator(top.system, options);
  const auto invariants = [&] {
    const Eigen::VectorXd &q = integrator.coordinates(), &v = integrator.velocities();
    const Eigen::Vector3d axis = fr::orientation_of(q).col(2);
    return Eigen::Vector3d(top.system.energies(q, v).total(), angular_momentum(top.model, q, v).z(),
                           angular_velocity(q, v).dot(axis));
  };
  const Eigen::Vector3d start = invariants();
  // Scales: the kinetic energy (gravity's share is 3 % of it), |L| ≈ I_3 ω, the spin.
  const double energy_scale = top.system.energies(integrator.coordinates(), integrator.velocities()).kinetic;
  const double momentum_scale = angular_momentum(top.model, integrator.coordinates(), integrator.velocities()).norm();
  Drift d;
  try {
    while (integrator.time() < 0.5 - 0.5 * step) {
      integrator.step();
      const Eigen::Vector3d now = invariants();
      d.energy = std::max(d.energy, std::abs(now(0) - start(0)) / energy_scale);
      d.momentum = std::max(d.momentum, std::abs(now(1) - start(1)) / momentum_scale);
      d.spin = std::max(d.spin, std::abs(now(2) - start(2)) / HeavyTop::kSpin);
    }
  } catch (const fr::StepFailure&) {
    d.failed = true;
  }
  return d;
}

}  // namespace

// The heavy top conserves its energy, its angular momentum about the vertical through the pivot (gravity's moment
// is horizontal) and its spin about its own axis (symmetric top). With ρ∞ = 1 and h = 1e-4 s (ω h = 0.015) over
// 0.5 s, measured: energy 1.3e-7 of the kinetic energy (2.3e-7 at h/2: Newton's tolerance, no drift), spin 2.2e-7
// (9.4e-8), and L_z 2.27e-5 of |L| falling to 5.71e-6 at h/2: the time discretisation's second-order error, as the
// top's path (bench/convergence_bench: 4.4e-6 m of a 0.1 m radius at 1e-4 s). The index-3 form gains 0.1 % energy at
// 0.11 s and stops at 0.16 s.
TEST(FastSpin, HeavyTopKeepsItsInvariantsAtRhoOne) {
  const Drift coarse = run_top(fr::ConstraintForm::stabilized_index2, 1e-4);
  const Drift fine = run_top(fr::ConstraintForm::stabilized_index2, 5e-5);
  for (const Drift& d : {coarse, fine}) {
    EXPECT_FALSE(d.failed);
    EXPECT_LT(d.energy, 2e-6);
    EXPECT_LT(d.spin, 2e-6);
  }
  EXPECT_LT(coarse.momentum, 5e-5);
  EXPECT_NEAR(coarse.momentum / fine.momentum, 4.0, 0.5);
  const Drift index3 = run_top(fr::ConstraintForm::index3, 1e-4);
  EXPECT_TRUE(index3.failed || index3.energy > 1e-3);
}

namespace {

// A free rigid steel plate 0.3 x 0.2 x 0.01 m spinning at 5 rad/s about its intermediate principal axis (y), with a
// 1 % disturbance: it flips every ~2.6 s. No force: energy and the angular momentum vector are invariants.
Drift run_plate(fr::ConstraintForm form, double rho, double* lowest_spin_y = nullptr, double step = 2e-3) {
  const double a = 0.3, b = 0.2, c = 0.01, mass = 7850.0 * a * b * c;
  const fr::BodyModel model = rigid(mass, mass / 12.0 * Eigen::Vector3d(a * a, b * b, c * c).asDiagonal());
  fr::System system;
  fr::BodyState state;
  state.angular_velocity = Eigen::Vector3d(0.05, 5.0, 0.05);
  system.add_body("plate", model, state);
  fr::GeneralizedAlphaOptions options;
  options.rho_infinity = rho;
  options.step = step;
  options.constraints = form;
  fr::GeneralizedAlpha integrator(system, options);
  const double e0 = system.energies(integrator.coordinates(), integrator.velocities()).total();
  const Eigen::Vector3d l0 = angular_momentum(model, integrator.coordinates(), integrator.velocities());
  Drift d;
  double lowest = 5.0;
  try {
    while (integrator.time() < 12.0 - 1e-3) {
      integrator.step();
      const Eigen::VectorXd &q = integrator.coordinates(), &v = integrator.velocities();
      d.energy = std::max(d.energy, std::abs(system.energies(q, v).total() - e0) / e0);
      d.momentum = std::max(d.momentum, (angular_momentum(model, q, v) - l0).norm() / l0.norm());
      lowest = std::min(lowest, (fr::orientation_of(q).transpose() * angular_velocity(q, v)).y());
    }
  } catch (const fr::StepFailure&) {
    d.failed = true;
  }
  if (lowest_spin_y) *lowest_spin_y = lowest;
  return d;
}

}  // namespace

// The plate flip: with ρ∞ = 0.99 and h = 2 ms the index-3 form ended a 12 s run at +17.6 % energy and +8 %
// |L| (exit 0; this analytic plate's index-3 run stops early instead), and stopped at 3.7 s with ρ∞ = 1. The
// stabilised form keeps both over 12 s and four flips (the body-frame spin about y reverses). Measured, ρ∞ = 1 and
// 0.99: energy 1.7e-7 (1.7e-11 with the Newton tolerance at 1e-10: no drift of its own), |ΔL|/|L| 8.0e-6 at any
// Newton tolerance and 2.0e-6 at h = 1 ms: a second-order error of the form (the position correction W Φ_qᵀ ν moves
// q without v), of the size of the index-3 form's at ρ∞ = 0.9 (4.2e-6, FbsimCli.AConservativeSceneThatGainsEnergy...).
TEST(FastSpin, FlippingPlateKeepsEnergyAndMomentum) {
  for (const double rho : {1.0, 0.99}) {
    SCOPED_TRACE(rho);
    double lowest = 0.0;
    const Drift d = run_plate(fr::ConstraintForm::stabilized_index2, rho, &lowest);
    EXPECT_FALSE(d.failed);
    EXPECT_LT(lowest, -4.9);  // it flipped: the spin about the body's y axis went from +5 to −5 rad/s
    EXPECT_LT(d.energy, 1e-6);
    EXPECT_LT(d.momentum, 2e-5);
  }
  const Drift half = run_plate(fr::ConstraintForm::stabilized_index2, 1.0, nullptr, 1e-3);
  EXPECT_LT(half.momentum, 5e-6);  // second order: 8.0e-6 → 2.0e-6
  const Drift index3 = run_plate(fr::ConstraintForm::index3, 0.99);
  EXPECT_TRUE(index3.failed || index3.energy > 1e-2);
}

namespace {

// A free 0.5 x 0.05 x 0.05 m steel beam (4 free-free modes, the first at ~1 kHz) tumbling at 150 rad/s about a
// transverse axis with a 1 % wobble, its first mode excited (tip amplitude ~0.1 mm).
Drift run_flexible_spin(fr::ConstraintForm form, double step = 1e-4) {
  static const fr::BodyModel model = [] {
    const fp::Material steel{"steel", 210e9, 0.3, 7850.0};
    const auto fe = flexbody::test::assemble(flexbody::test::box_mesh(0.5, 0.05, 0.05, 10, 2, 2), steel);
    const flexbody::format::BodyData b = flexbody::test::free_free_body(fe, steel, 4);
    return fr::make_body_model(b, std::nullopt, "beam");
  }();
  fr::BodyState state;
  state.angular_velocity = Eigen::Vector3d(1.5, 0.0, 150.0);
  state.xi = Eigen::VectorXd::Zero(3 * model.field_count());
  for (Eigen::Index f = 0; f < model.field_count(); ++f)
    state.xi.segment<3>(3 * f) = 1e-3 * model.mode_coefficients.block<1, 3>(f, 0).transpose();
  fr::System system;
  system.add_body("beam", model, state);
  fr::GeneralizedAlphaOptions options;
  options.rho_infinity = 1.0;
  options.step = step;
  options.constraints = form;
  fr::GeneralizedAlpha integrator(system, options);
  const double e0 = system.energies(integrator.coordinates(), integrator.velocities()).total();
  const Eigen::Vector3d l0 = angular_momentum(model, integrator.coordinates(), integrator.velocities());
  Drift d;
  try {
    while (integrator.time() < 0.5 - 0.5 * step) {
      integrator.step();
      const Eigen::VectorXd &q = integrator.coordinates(), &v = integrator.velocities();
      d.energy = std::max(d.energy, std::abs(system.energies(q, v).total() - e0) / e0);
      d.momentum = std::max(d.momentum, (angular_momentum(model, q, v) - l0).norm() / l0.norm());
    }
  } catch (const fr::StepFailure&) {
    d.failed = true;
  }
  return d;
}

}  // namespace

// The spin loads the beam: its elastic energy swings between 0 and 2 % of the total, in its first mode (~1 kHz,
// ω₁ h = 0.6 at h = 1e-4 s: not resolved) and above. With ρ∞ = 1 the energy error oscillates without growing;
// measured over 0.5 s: energy 1.67e-4, |ΔL|/|L| 7.4e-5, and 3.7e-5, 1.7e-5 at h/2 (second order, 4.6x and 4.4x).
// The index-3 form stops at ρ∞ = 1 (its energy had grown by 3.1e-3).
TEST(FastSpin, TumblingFlexibleBeamKeepsEnergyAndMomentum) {
  const Drift coarse = run_flexible_spin(fr::ConstraintForm::stabilized_index2, 1e-4);
  const Drift fine = run_flexible_spin(fr::ConstraintForm::stabilized_index2, 5e-5);
  EXPECT_FALSE(coarse.failed);
  EXPECT_FALSE(fine.failed);
  EXPECT_LT(coarse.energy, 3e-4);
  EXPECT_LT(coarse.momentum, 1.5e-4);
  EXPECT_GT(coarse.energy / fine.energy, 3.0);
  EXPECT_GT(coarse.momentum / fine.momentum, 3.0);
  const Drift index3 = run_flexible_spin(fr::ConstraintForm::index3, 1e-4);
  EXPECT_TRUE(index3.failed || index3.energy > 1e-3);
}

// Consistent initial velocities close the joints with the rigid velocities where they can. A flexible beam given only
// its spin, 150 rad/s about z, and held at one end by a revolute joint about z: driven at 150 rad/s, it starts turning
// rigidly about the pin (its centre of mass at Ω L/2); free to turn, with the rigid velocities nearest in M, which is
// what an impulse at the pin gives (the angular momentum about the pin kept: ω' = ω J_zz / (J_zz + m L²/4)). In both,
// no deformation rate. (At this point marker the M-nearest correction over all velocities is the same to 3 digits; at
// an rbe3 interface, whose rotation the modes move cheaply, it was not: tests/preprocess/scale_invariance_test.cpp.)
TEST(FastSpin, APinnedBeamGivenOnlyItsSpinStartsWithItsRigidVelocity) {
  const fp::Material steel{"steel", 210e9, 0.3, 7850.0};
  const auto fe = flexbody::test::assemble(flexbody::test::box_mesh(0.5, 0.05, 0.05, 10, 2, 2), steel);
  const fr::BodyModel model = fr::make_body_model(flexbody::test::free_free_body(fe, steel, 4), std::nullopt, "beam");
  for (const bool driven : {true, false}) {
    SCOPED_TRACE(driven ? "driven" : "free to turn");
    fr::BodyState state;
    state.angular_velocity = Eigen::Vector3d(0.0, 0.0, 150.0);
    fr::System system;
    const int b = system.add_body("beam", model, state);
    const Eigen::VectorXd q0 = system.initial_coordinates();
    // The pin and the far end: points of the body frame (origin at the centre of mass) on its axis.
    const fr::Marker pin = fr::point_marker(model, b, "beam", Eigen::Vector3d(-0.25, 0.0, 0.0));
    const fr::Marker end = fr::point_marker(model, b, "beam", Eigen::Vector3d(0.25, 0.0, 0.0));
    system.add_joint(fr::make_joint("pin", driven ? fr::JointType::driven_revolute : fr::JointType::revolute, pin,
                                    fr::ground_marker(fr::marker_position(pin, q0)), Eigen::Vector3d::UnitZ(), q0,
                                    Eigen::VectorXd(), [](double t) { return 150.0 * t; }, [](double) { return 150.0; }));
    fr::GeneralizedAlphaOptions options;
    options.step = 1e-4;
    const fr::GeneralizedAlpha integrator(system, options);
    const Eigen::VectorXd v_b = system.body_coordinates(integrator.velocities(), b);
    const Eigen::VectorXd q_b = system.body_coordinates(integrator.coordinates(), b);
    const Eigen::Matrix3d j = model.mass_matrix.block<3, 3>(1, 1);  // ∫ x̄ x̄ᵀ dm about the centre of mass
    const double j_zz = j(0, 0) + j(1, 1);
    const double spin = driven ? 150.0 : 150.0 * j_zz / (j_zz + model.mass * 0.25 * 0.25);
    EXPECT_NEAR(v_b(1), spin * 0.25, 1e-9 * 37.5);                                // the centre of mass, along y
    EXPECT_LT(v_b.tail(v_b.size() - 12).cwiseAbs().maxCoeff(), 1e-12 * 37.5);     // no deformation rate
    const Eigen::Vector3d far = fr::marker_position_jacobian(end, q_b) * v_b;
    EXPECT_NEAR(far.y(), spin * 0.5, 1e-9 * 75.0);
    EXPECT_LT(std::abs(far.x()) + std::abs(far.z()), 1e-9 * 75.0);
  }
}
