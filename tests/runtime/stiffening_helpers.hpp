#pragma once
// What stiffening_test.cpp and stiffening_reference_test.cpp share: the cantilever made by fbprep, the rotating beam's
// frequencies, the models and the frequency measured from free vibration.
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

namespace stiffening {

namespace fr = flexbody::runtime;

inline constexpr double kSouthwell = 1.1933;  // the first bending mode of a uniform cantilever, hub radius 0

// A steel beam 1 x 0.03 x 0.02 m along x (flapwise: z, the thin direction; lead-lag: y), Craig-Bampton with an rbe2
// root at x = 0 and 6 fixed-interface modes, quadratic tetrahedra of 0.01 m, with the geometric stiffness.
inline const std::filesystem::path& beam_folder() {
  static const std::filesystem::path folder = [] {
    const auto dir = flexbody::test::scratch_dir();
    flexbody::test::write_text(dir / "beam.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 0.03, 0.02};\n");
    flexbody::test::write_text(dir / "beam.yaml", R"(input: beam.geo
unit: m
material: steel
mesh: {size: 0.01}
reduction: {kind: craig-bampton, modes: 6}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}, coupling: rbe2}
  tip: {select: {plane: {point: [1, 0, 0], normal: [1, 0, 0]}}, coupling: rbe3}
geometric_stiffness: true
)");
    const flexbody::test::CliRun prep = flexbody::test::run_fbprep(dir, "beam.yaml -o beam.fbh5 -q");
    EXPECT_EQ(prep.exit_code, 0) << prep.err;
    return dir;
  }();
  return folder;
}

inline const flexbody::format::BodyData& beam() {
  static const flexbody::format::BodyData data = flexbody::format::read_body_file(beam_folder() / "beam.fbh5");
  return data;
}

// The first bending frequency of a uniform Euler-Bernoulli cantilever spinning about an axis through its root
// (normal to the beam), over its value at rest, for the spin Ω in units of the frequency at rest: flapwise
// EI w⁗ − (N w′)′ + m ẅ = 0 with the tension N(x) = m Ω² (L² − x²)/2; lead-lag the same with −m Ω² w added.
// Rayleigh-Ritz with the clamped polynomials x², ..., x⁹ in units EI = m = L = 1, where the integrals are exact.
// Independent of flexbody: it reproduces the clamped beam's (β₁L)² = 3.5160 at rest (checked below), and its
// slope in Ω² at small spin is Southwell's S.
inline double beam_frequency(double spin, bool lead_lag) {
  constexpr int n = 8;
  Eigen::MatrixXd k(n, n), g(n, n), m(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double p = i + 2, q = j + 2;
      k(i, j) = p * (p - 1) * q * (q - 1) / (p + q - 3);
      g(i, j) = 0.5 * p * q * (1 / (p + q - 1) - 1 / (p + q + 1));  // ∫ (1 − x²)/2 φ_i′ φ_j′
      m(i, j) = 1 / (p + q + 1);
    }
  Eigen::MatrixXd stiffness = k + spin * spin * g;
  if (lead_lag) stiffness -= spin * spin * m;
  return std::sqrt(
      Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd>(stiffness, m, Eigen::EigenvaluesOnly).eigenvalues()(0));
}

// Its ratio ω(Ω)/ω(0) for Ω in units of ω(0).
inline double beam_frequency_ratio(double spin_over_rest, bool lead_lag) {
  const double rest = beam_frequency(0.0, lead_lag);
  return beam_frequency(spin_over_rest * rest, lead_lag) / rest;
}

enum class Formulation { gcms, ffrf_mean_axis, ffrf_root };
enum class Direction { flapwise, lead_lag };

inline fr::BodyModel model_of(Formulation formulation, bool stiffening) {
  fr::BodyModel model = fr::make_body_model(beam(), std::nullopt, "beam");
  if (!stiffening) model.prestress.reset();
  if (formulation == Formulation::ffrf_mean_axis)
    model.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(model, fr::FloatingFrame::mean_axis));
  if (formulation == Formulation::ffrf_root)
    model.floating_frame =
        std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(model, fr::FloatingFrame::interface, "root"));
  return model;
}

// The first bending frequency [rad/s] in the rotating frame of the beam spinning about z at its root at `spin`
// [rad/s], from free vibration after a pulse at the tip: the rotating-frame tip displacement's zero crossings over
// about ten periods, 100 steps per expected period (trapezoidal rule: period error (ω h)²/12 = 3e-4).
inline double measured_frequency(Formulation formulation, Direction direction, double spin, double expected, bool stiffening = true) {
  const fr::BodyModel model = model_of(formulation, stiffening);
  const int axis = direction == Direction::flapwise ? 2 : 1;
  fr::BodyState state;
  const Eigen::Vector3d root_offset = model.interfaces[0].y_row.segment<3>(1);  // X̄ of the root (the centre of mass is 0)
  state.angular_velocity = Eigen::Vector3d(0, 0, spin);
  state.velocity = state.angular_velocity.cross(-root_offset);
  fr::System system;
  const int b = system.add_body("beam", model, state);
  const Eigen::VectorXd q0 = system.initial_coordinates();
  const fr::Marker root = fr::interface_marker(model, b, "beam", "root");
  const fr::Marker tip = fr::interface_marker(model, b, "beam", "tip");
  system.add_joint(fr::make_joint("hub", fr::JointType::driven_revolute, root, fr::ground_marker(fr::marker_position(root, q0)),
                                  Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd(), [spin](double t) { return spin * t; }));
  const Eigen::Vector3d hub = fr::marker_position(root, q0);
  // A half-sine pulse at the tip along the axis of the rotating frame, a quarter of the expected period long: it
  // excites the first mode and hardly the second (6.3 times higher, about a fortieth of the tip's static response).
  const double pulse = 0.5 * std::numbers::pi / expected;
  system.add_force({tip, [=](double t) -> Eigen::Vector3d {
                      if (t >= pulse) return Eigen::Vector3d::Zero();
                      const double f = 100.0 * std::sin(std::numbers::pi * t / pulse);  // [N]
                      if (axis == 2) return Eigen::Vector3d(0, 0, f);
                      return Eigen::Vector3d(-f * std::sin(spin * t), f * std::cos(spin * t), 0);
                    }});
  fr::GeneralizedAlphaOptions options;
  options.rho_infinity = 0.9;
  // 100 steps per period, and at most 0.025 rad of spin per step (the GCMS body's Newton iteration diverges at
  // 0.05 rad per step on this beam, with or without stiffening).
  options.step = std::min(2 * std::numbers::pi / expected / 100, spin > 0.0 ? 0.025 / spin : 1.0);
  options.spin_warning = options.spin_limit = 0.0;
  fr::GeneralizedAlpha integrator(system, options);
  // The tip's displacement along the axis in the hub's rotating frame.
  auto displacement = [&](double t, const Eigen::VectorXd& q) {
    const Eigen::Vector3d p = fr::marker_position(tip, system.body_coordinates(q, b)) - hub;
    const double c = std::cos(spin * t), s = std::sin(spin * t);
    const Eigen::Vector3d rotating(c * p.x() + s * p.y(), -s * p.x() + c * p.y(), p.z());
    return rotating(axis);
  };
  std::vector<double> crossings;
  double previous = displacement(0.0, integrator.coordinates());
  while (integrator.time() < pulse + 10.3 * 2 * std::numbers::pi / expected) {
    integrator.step();
    const double now = displacement(integrator.time(), integrator.coordinates());
    if (integrator.time() > pulse && (now > 0) != (previous > 0))
      crossings.push_back(integrator.time() - options.step * now / (now - previous));
    previous = now;
  }
  if (crossings.size() < 4) {
    ADD_FAILURE() << crossings.size() << " zero crossings";
    return 0.0;
  }
  const double period = (crossings.back() - crossings.front()) / (0.5 * static_cast<double>(crossings.size() - 1));
  return 2 * std::numbers::pi / period;
}

}  // namespace stiffening
