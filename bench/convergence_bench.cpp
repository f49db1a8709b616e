// convergence_bench: the time integrator's error against the step size at its default settings, on scenes with
// independent references, with the Newton iterations and the cost that each accuracy takes. Prints a table and
// writes CSV for bench/convergence_plot.py.
//
//   convergence_bench OUTPUT.csv [--quick]
//
// Scenes (every one at the integrator's defaults except the step; ρ∞ = 0.9):
// - rigid pendulum: the 1 x 0.05 x 0.05 m steel bar of the validation data pinned at one end about z, released
//   horizontal; error of the centre of mass at t = 1 s against the exact motion, θ'' = −(m g d / I_p) cos θ,
//   integrated by RK4 at 1 µs in long double (its own error is ~1e-18).
// - heavy top: a rigid cylinder (r = 0.05 m, h = 0.2 m, 12.3 kg) on a spherical joint at the centre of its base,
//   its axis 30° from the vertical, spinning at 150 rad/s about it; error of the top's centre of mass at t = 0.5 s
//   against Euler's equations with unit quaternions, RK4 at 0.5 µs.
// - flexible pendulum: a 0.5 x 0.05 x 0.05 m steel beam (4 free-free modes, Rayleigh damping β = 1e-5 s) pinned at
//   a corner node about z, released horizontal; error of the far corner at t = 0.25 s against the same model at a quarter of the smallest
//   step with the Newton tolerance at 1e-3 of the default.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/box_mesh.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/gcms_constants.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "flexbody/runtime/damping.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"

#include <Eigen/Geometry>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace fr = flexbody::runtime;
namespace fp = flexbody::preprocess;

namespace {

constexpr double kGravity = 9.81;

// ---------- rigid pendulum ----------
constexpr double kBarLength = 1.0, kBarWidth = 0.05, kBarMass = 19.625;

fr::BodyModel rigid_model(double mass, const Eigen::Matrix3d& second_moment) {
  return fr::rigid_body_model(mass, second_moment, "rigid");  // J = ∫ x xᵀ dm
}

std::unique_ptr<fr::System> rigid_pendulum() {
  const double l = kBarLength, w = kBarWidth;
  auto system = std::make_unique<fr::System>();
  fr::BodyState state;
  state.position = Eigen::Vector3d(l / 2, 0, 0);
  const Eigen::Matrix3d j = kBarMass / 12.0 * Eigen::Vector3d(l * l, w * w, w * w).asDiagonal();
  const fr::BodyModel model = rigid_model(kBarMass, j);
  const int bar = system->add_body("bar", model, state);
  const fr::Marker pin = fr::point_marker(system->model(bar), bar, "bar", Eigen::Vector3d(-l / 2, 0, 0));
  system->add_joint(fr::make_joint("pivot", fr::JointType::revolute, pin, fr::ground_marker(Eigen::Vector3d::Zero()),
                                   Eigen::Vector3d::UnitZ(), system->initial_coordinates(), Eigen::VectorXd()));
  system->set_gravity(Eigen::Vector3d(0, -kGravity, 0));
  return system;
}

// θ'' = −k cos θ from θ = 0 at rest, RK4 in long double; returns the centre of mass at t.
Eigen::Vector3d rigid_pendulum_reference(double t_end) {
  const long double l = kBarLength, w = kBarWidth, d = l / 2;
  const long double inertia = kBarMass * (l * l + w * w) / 12.0L + kBarMass * d * d;
  const long double k = kBarMass * kGravity * d / inertia;
  long double theta = 0, rate = 0;
  const long steps = std::lround(t_end / 1e-6);
  const long double h = static_cast<long double>(t_end) / steps;
  auto acc = [k](long double th) { return -k * std::cos(th); };
  for (long i = 0; i < steps; ++i) {
    const long double k1t = rate, k1r = acc(theta);
    const long double k2t = rate + h / 2 * k1r, k2r = acc(theta + h / 2 * k1t);
    const long double k3t = rate + h / 2 * k2r, k3r = acc(theta + h / 2 * k2t);
    const long double k4t = rate + h * k3r, k4r = acc(theta + h * k3t);
    theta += h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
    rate += h / 6 * (k1r + 2 * k2r + 2 * k3r + k4r);
  }
  return Eigen::Vector3d(static_cast<double>(d * std::cos(theta)), static_cast<double>(d * std::sin(theta)), 0.0);
}

// ---------- heavy top ----------
constexpr double kTopRadius = 0.05, kTopHeight = 0.2, kTopDensity = 7850.0, kTopSpin = 150.0, kTopTilt = 30.0;

double top_mass() { return kTopDensity * std::numbers::pi * kTopRadius * kTopRadius * kTopHeight; }
// About the centre of mass, body axes with z the symmetry axis.
Eigen::Matrix3d top_inertia() {
  const double m = top_mass(), r = kTopRadius, h = kTopHeight;
  const double across = m * (3 * r * r + h * h) / 12.0, along = m * r * r / 2.0;
  return Eigen::Vector3d(across, across, along).asDiagonal();
}
Eigen::Matrix3d top_orientation() {
  return Eigen::AngleAxisd(kTopTilt * std::numbers::pi / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

std::unique_ptr<fr::System> heavy_top() {
  const Eigen::Matrix3d inertia = top_inertia();
  // J = ½ tr(I) I − I for the second-moment matrix.
  const Eigen::Matrix3d second = 0.5 * inertia.trace() * Eigen::Matrix3d::Identity() - inertia;
  auto system = std::make_unique<fr::System>();
  fr::BodyState state;
  state.orientation = top_orientation();
  state.position = state.orientation * Eigen::Vector3d(0, 0, kTopHeight / 2);
  state.angular_velocity = state.orientation * Eigen::Vector3d(0, 0, kTopSpin);
  const int top = system->add_body("top", rigid_model(top_mass(), second), state);
  const fr::Marker tip = fr::point_marker(system->model(top), top, "top", Eigen::Vector3d(0, 0, -kTopHeight / 2));
  system->add_joint(fr::make_joint("tip", fr::JointType::spherical, tip, fr::ground_marker(Eigen::Vector3d::Zero()),
                                   Eigen::Vector3d::UnitZ(), system->initial_coordinates(), Eigen::VectorXd()));
  system->set_gravity(Eigen::Vector3d(0, 0, -kGravity));
  return system;
}

// Euler's equations about the fixed point with unit quaternions, RK4 in long double; the centre of mass at t.
Eigen::Vector3d heavy_top_reference(double t_end) {
  using Vec = Eigen::Matrix<long double, 3, 1>;
  using Quat = Eigen::Quaternion<long double>;
  const long double m = top_mass(), c = kTopHeight / 2;
  Eigen::Matrix<long double, 3, 3> ip = top_inertia().cast<long double>();
  ip(0, 0) += m * c * c;
  ip(1, 1) += m * c * c;
  const Eigen::Matrix<long double, 3, 3> ip_inv = ip.inverse();
  const Vec com(0, 0, c), gravity(0, 0, -kGravity);
  struct State {
    Quat q;
    Vec w;  // body axes
  };
  auto rate = [&](const State& s) {
    const Eigen::Matrix<long double, 3, 3> r = s.q.normalized().toRotationMatrix();
    const Vec torque = com.cross(r.transpose() * (m * gravity));
    const Vec w_dot = ip_inv * (torque - s.w.cross(ip * s.w));
    const Quat half_w(0, s.w.x() / 2, s.w.y() / 2, s.w.z() / 2);
    const Quat q_dot = s.q * half_w;
    return std::pair<Eigen::Matrix<long double, 4, 1>, Vec>(q_dot.coeffs(), w_dot);
  };
  State s{Quat(top_orientation().cast<long double>()), Vec(0, 0, kTopSpin)};
  const long steps = std::lround(t_end / 5e-7);
  const long double h = static_cast<long double>(t_end) / steps;
  auto add = [](const State& s0, const std::pair<Eigen::Matrix<long double, 4, 1>, Vec>& d, long double f) {
    State out = s0;
    out.q.coeffs() += f * d.first;
    out.w += f * d.second;
    return out;
  };
  for (long i = 0; i < steps; ++i) {
    const auto k1 = rate(s), k2 = rate(add(s, k1, h / 2)), k3 = rate(add(s, k2, h / 2)), k4 = rate(add(s, k3, h));
    s.q.coeffs() += h / 6 * (k1.first + 2 * k2.first + 2 * k3.first + k4.first);
    s.w += h / 6 * (k1.second + 2 * k2.second + 2 * k3.second + k4.second);
    s.q.normalize();
  }
  return (s.q.toRotationMatrix() * com).cast<double>();
}

// ---------- flexible pendulum ----------
// Rayleigh damping β = 1e-5 s: ζ = 0.05 in the first mode (1.6 kHz), overdamped above 32 kHz. The generalized basis
// of the improved GCMS holds fields up to ~1e5 Hz (formulations.md, "The Method": the fields' spectrum), which the
// sudden release excites; no step here resolves them, and undamped their response converges erratically (measured:
// orders −1.2 to 3.4).
constexpr double kBeamRayleighBeta = 1e-5;
const fr::BodyModel& flexible_beam() {
  static const fr::BodyModel model = [] {
    const fp::Material steel{"steel", 210e9, 0.3, 7850.0};
    fp::TetMesh mesh = fp::box_mesh(0.5, 0.05, 0.05, 10, 2, 2);
    const fp::NodeGraph graph = fp::NodeGraph::build(mesh);
    const auto geometry = fp::element_geometries(mesh);
    const fp::SparseMatrix k = fp::assemble_stiffness(mesh, graph, geometry, steel);
    const fp::SparseMatrix m = fp::assemble_scalar_mass(mesh, graph, geometry, steel.density, fp::MassScheme::consistent);
    flexbody::format::BodyData b;
    b.mass = fp::mass_properties(m, mesh.nodes);
    b.mesh.nodes = mesh.nodes.rowwise() - b.mass.center_of_mass_input.transpose();
    b.mesh.tets = mesh.tets;
    fp::FreeFreeOptions options;
    options.modes = 4;
    const fp::FreeFreeModes modes = fp::free_free_modes(b.mesh.nodes, k, m, steel, options);
    b.modes.frequencies_hz = modes.frequencies_hz;
    b.modes.relative_residuals = modes.relative_residuals;
    b.modes.upsilon = fp::upsilon_from_modes(modes.vectors);
    b.gcms = fp::gcms_constants(k, m, b.mesh.nodes, b.modes.upsilon);
    fr::BodyModel body = fr::make_body_model(b, std::nullopt, "beam");
    body.damping = fr::rayleigh_damping(body, 0.0, kBeamRayleighBeta);
    return body;
  }();
  return model;
}

Eigen::Index far_corner() {
  Eigen::Index corner = 0;
  flexible_beam().nodes.rowwise().sum().maxCoeff(&corner);
  return corner;
}

std::unique_ptr<fr::System> flexible_pendulum() {
  const fr::BodyModel& model = flexible_beam();
  auto system = std::make_unique<fr::System>();
  const int b = system->add_body("beam", model, fr::BodyState{});
  Eigen::Index corner = 0;
  model.nodes.rowwise().sum().minCoeff(&corner);
  const fr::Marker pin = fr::node_marker(system->model(b), b, "beam", corner);
  const Eigen::VectorXd q0 = system->initial_coordinates();
  system->add_joint(fr::make_joint("pin", fr::JointType::revolute, pin, fr::ground_marker(fr::marker_position(pin, q0)),
                                   Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd()));
  system->set_gravity(Eigen::Vector3d(0, -kGravity, 0));
  return system;
}

// ---------- runs ----------
struct Scene {
  std::string name;
  std::function<std::unique_ptr<fr::System>()> make;
  std::function<Eigen::Vector3d(const fr::System&, const Eigen::VectorXd&)> observe;  ///< the point compared [m]
  double end = 0.0;
  std::vector<double> steps;
  Eigen::Vector3d reference;
};

struct Result {
  Eigen::Vector3d point;
  double iterations_per_step = 0.0, microseconds_per_step = 0.0;
  bool failed = false;
  std::string failure;
};

Result run(const Scene& scene, const fr::GeneralizedAlphaOptions& options) {
  const std::unique_ptr<fr::System> system = scene.make();
  Result r;
  try {
    fr::GeneralizedAlpha integrator(*system, options);
    const long steps = std::lround(scene.end / options.step);
    const auto start = std::chrono::steady_clock::now();
    for (long i = 0; i < steps; ++i) integrator.step();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.point = scene.observe(*system, integrator.coordinates());
    r.iterations_per_step = static_cast<double>(integrator.total_iterations()) / static_cast<double>(steps);
    r.microseconds_per_step = 1e6 * seconds / static_cast<double>(steps);
  } catch (const std::exception& e) {
    r.failed = true;
    r.failure = e.what();
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: convergence_bench OUTPUT.csv [--quick] [--index3] [--fresh] [--tolerance T] [--rho R]\n");
    return 2;
  }
  bool quick = false;
  fr::GeneralizedAlphaOptions defaults;  // the integrator's defaults, but for what the command line sets
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) quick = true;
    else if (std::strcmp(argv[i], "--index3") == 0) defaults.constraints = fr::ConstraintForm::index3;
    else if (std::strcmp(argv[i], "--fresh") == 0) defaults.reuse_newton_matrix = false;
    else if (std::strcmp(argv[i], "--tolerance") == 0 && i + 1 < argc) defaults.tolerance = std::atof(argv[++i]);
    else if (std::strcmp(argv[i], "--rho") == 0 && i + 1 < argc) defaults.rho_infinity = std::atof(argv[++i]);
    else {
      std::fprintf(stderr, "convergence_bench: unknown argument '%s'\n", argv[i]);
      return 2;
    }
  }
  const std::vector<double> fine{2e-4, 1e-4, 5e-5, 2.5e-5, 1e-5};
  std::vector<Scene> scenes;
  scenes.push_back({"rigid pendulum", rigid_pendulum,
                    [](const fr::System&, const Eigen::VectorXd& q) { return Eigen::Vector3d(q.head<3>()); }, 1.0,
                    quick ? std::vector<double>{2e-4, 1e-4, 5e-5} : fine, rigid_pendulum_reference(1.0)});
  scenes.push_back({"heavy top", heavy_top,
                    [](const fr::System&, const Eigen::VectorXd& q) { return Eigen::Vector3d(q.head<3>()); }, 0.5,
                    quick ? std::vector<double>{2e-4, 1e-4, 5e-5} : fine, heavy_top_reference(0.5)});
  auto corner_of = [](const fr::System& s, const Eigen::VectorXd& q) {
    const fr::Marker m = fr::node_marker(s.model(0), 0, "beam", far_corner());
    return fr::marker_position(m, s.body_coordinates(q, 0));
  };
  scenes.push_back({"flexible pendulum", flexible_pendulum, corner_of, 0.25,
                    quick ? std::vector<double>{4e-4, 2e-4, 1e-4} : std::vector<double>{4e-4, 2e-4, 1e-4, 5e-5, 2.5e-5},
                    Eigen::Vector3d::Zero()});
  {  // the flexible pendulum's reference: the same model at a quarter of the smallest step, a tight Newton test
    Scene& s = scenes.back();
    fr::GeneralizedAlphaOptions tight = defaults;
    tight.step = s.steps.back() / 4;
    tight.tolerance *= 1e-3;
    const Result ref = run(s, tight);
    if (ref.failed) {
      std::fprintf(stderr, "convergence_bench: the flexible reference failed, scene skipped: %s\n", ref.failure.c_str());
      scenes.pop_back();
    } else {
      s.reference = ref.point;
    }
  }
  std::ofstream csv(argv[1]);
  csv << "scene,step_s,error_m,order,newton_iterations_per_step,us_per_step\n";
  std::printf("%-18s %10s %12s %6s %10s %10s\n", "scene", "h [s]", "error [m]", "order", "iter/step", "us/step");
  for (const Scene& s : scenes) {
    double previous_error = 0.0, previous_step = 0.0;
    for (double h : s.steps) {
      fr::GeneralizedAlphaOptions options = defaults;
      options.step = h;
      const Result r = run(s, options);
      if (r.failed) {
        std::printf("%-18s %10.3g  failed: %s\n", s.name.c_str(), h, r.failure.c_str());
        csv << s.name << ',' << h << ",nan,nan,nan,nan\n";
        previous_error = 0.0;
        continue;
      }
      const double error = (r.point - s.reference).norm();
      const double order = previous_error > 0.0 ? std::log(previous_error / error) / std::log(previous_step / h) : NAN;
      std::printf("%-18s %10.3g %12.3e %6.2f %10.2f %10.1f\n", s.name.c_str(), h, error, order, r.iterations_per_step,
                  r.microseconds_per_step);
      csv << s.name << ',' << h << ',' << error << ',' << (std::isnan(order) ? std::string("") : std::to_string(order))
          << ',' << r.iterations_per_step << ',' << r.microseconds_per_step << '\n';
      previous_error = error;
      previous_step = h;
    }
  }
  return 0;
}
