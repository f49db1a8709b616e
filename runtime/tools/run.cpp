#include "run.hpp"

#include "flexbody/runtime/ffrf_dynamics.hpp"
#include "flexbody/runtime/gcms_elastic.hpp"
#include "flexbody/runtime/paraview_series.hpp"
#include "flexbody/runtime/reference_constraints.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <system_error>

namespace flexbody::fbsim {
namespace {

// One CSV file per output; values with 17 significant digits (round-trip exact).
class CsvFile {
 public:
  CsvFile(const std::filesystem::path& path, const std::vector<std::string>& columns) : out_(path) {
    if (!out_) throw std::runtime_error(path.string() + ": cannot write");
    out_ << "t [s]";
    for (const std::string& c : columns) out_ << ',' << c;
    out_ << '\n';
  }
  void row(double t, const Eigen::VectorXd& values) {
    out_ << fmt::format("{:.17g}", t);
    for (Eigen::Index k = 0; k < values.size(); ++k) out_ << fmt::format(",{:.17g}", values(k));
    out_ << '\n';
  }

 private:
  std::ofstream out_;
};

std::vector<std::string> columns_of(const Scene& scene, const Sensor& s) {
  std::vector<std::string> columns;
  for (const std::string& q : s.quantities) {
    if (q == "position") columns.insert(columns.end(), {"x [m]", "y [m]", "z [m]"});
    if (q == "velocity") columns.insert(columns.end(), {"vx [m/s]", "vy [m/s]", "vz [m/s]"});
    if (q == "reaction_force") columns.insert(columns.end(), {"fx [N]", "fy [N]", "fz [N]"});
    if (q == "reaction_moment") columns.insert(columns.end(), {"mx [N m]", "my [N m]", "mz [N m]"});
    if (q == "orientation")  // the marker frame's rotation matrix, row by row
      for (int i = 1; i <= 3; ++i)
        for (int j = 1; j <= 3; ++j) columns.push_back(fmt::format("R{}{} [1]", i, j));
    if (q == "displacement" || q == "stress") {
      const auto& region = scene.system.model(s.body).recovery[s.region];
      static constexpr const char* kComponents[] = {"xx", "yy", "zz", "xy", "xz", "yz"};
      for (Eigen::Index j = 0; j < region.nodes.size(); ++j) {
        if (q == "displacement")
          for (const char* c : {"x", "y", "z"}) columns.push_back(fmt::format("u{}_{} [m]", c, region.nodes(j)));
        else
          for (const char* c : kComponents) columns.push_back(fmt::format("s{}_{} [Pa]", c, region.nodes(j)));
      }
    }
    if (q == "modal_coordinates")
      for (Eigen::Index m = 0; m < scene.system.model(s.body).modes; ++m)
        columns.push_back(fmt::format("eta_{} [kg^1/2 m]", m + 1));
  }
  return columns;
}

Eigen::VectorXd values_of(const Scene& scene, const Sensor& s, const runtime::GeneralizedAlpha& integrator) {
  const runtime::System& system = scene.system;
  std::vector<double> values;
  auto push = [&values](const Eigen::VectorXd& v) { values.insert(values.end(), v.data(), v.data() + v.size()); };
  for (const std::string& q : s.quantities) {
    if (q == "position")
      push(runtime::marker_position(s.marker, system.body_coordinates(integrator.coordinates(), s.marker.body)));
    if (q == "velocity")  // ṙ = ∂r/∂q_b q̇_b
      push(runtime::marker_position_jacobian(s.marker, system.body_coordinates(integrator.coordinates(), s.marker.body)) *
           system.body_coordinates(integrator.velocities(), s.marker.body));
    if (q == "orientation") {  // A (I + [θ̄]×) with θ̄ = R ξ̄: the marker frame (to first order in θ̄)
      const Eigen::VectorXd q_b = system.body_coordinates(integrator.coordinates(), s.marker.body);
      Eigen::Matrix3d frame;
      for (int k = 0; k < 3; ++k) frame.col(k) = runtime::marker_direction(s.marker, q_b, Eigen::Vector3d::Unit(k));
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> rows = frame;
      push(Eigen::Map<const Eigen::Matrix<double, 9, 1>>(rows.data()));
    }
    if (q == "displacement" || q == "stress") {  // body axes: ū_i = Σ_f Ῡ'(i, f) ξ̄_f, σ̄ = S ξ̄ (SCHEMA.md)
      const runtime::BodyModel& model = system.model(s.body);
      const auto& region = model.recovery[s.region];
      const Eigen::VectorXd q_b = system.body_coordinates(integrator.coordinates(), s.body);
      // A floating-frame body: ξ̄ = Σ η_m c_m, and in an interface frame the modes' rigid part moves the nodes too.
      const Eigen::VectorXd xi_bar = model.floating()
                                         ? runtime::ffrf_field_coordinates(*model.floating_frame, q_b)
                                         : runtime::body_frame_coordinates(runtime::orientation_of(q_b), q_b.tail(q_b.size() - 12));
      if (q == "stress") {
        push(region.stress_modes * xi_bar);
      } else {
        const Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>> fields_xi(xi_bar.data(), 3, model.field_count());
        Eigen::VectorXd u(3 * region.nodes.size());
        for (Eigen::Index j = 0; j < region.nodes.size(); ++j) {
          u.segment<3>(3 * j) = fields_xi * runtime::field_row(model, region.nodes(j)).transpose();
          if (model.floating())
            for (Eigen::Index m = 0; m < model.modes; ++m) {
              const auto w = model.floating_frame->shapes.middleCols<3>(3 * m);
              u.segment<3>(3 * j) += q_b(7 + m) * (w.row(0).transpose() + w.middleRows<3>(1).transpose() *
                                                                              model.nodes.row(region.nodes(j)).transpose());
            }
        }
        push(u);
      }
    }
    if (q == "reaction_force" || q == "reaction_moment") {  // the joint's wrench on marker 1's body, at the marker
      const runtime::JointReaction r =
          system.joint_reaction(s.joint, integrator.time(), integrator.coordinates(), integrator.multipliers());
      push(q == "reaction_force" ? r.force : r.moment);
    }
    if (q == "modal_coordinates") {
      const runtime::BodyModel& model = system.model(s.body);
      const Eigen::VectorXd q_b = system.body_coordinates(integrator.coordinates(), s.body);
      if (model.floating()) {  // η itself
        push(q_b.tail(model.modes));
        continue;
      }
      const Eigen::Matrix3d a = runtime::orientation_of(q_b);
      Eigen::VectorXd eta = Eigen::VectorXd::Zero(model.modes);
      for (Eigen::Index m = 0; m < model.modes; ++m)
        for (Eigen::Index f = 0; f < model.field_count(); ++f)
          eta(m) += model.mode_coefficients.block<1, 3>(f, 3 * m).dot(a.transpose() * q_b.segment<3>(12 + 3 * f));
      push(eta);
    }
  }
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

// Monitors: energies, the largest ‖AᵀA − I‖_F, the largest Tisserand and joint residuals, Newton iterations.
Eigen::VectorXd monitor_values(const Scene& scene, const runtime::GeneralizedAlpha& integrator) {
  const runtime::System& system = scene.system;
  const runtime::Energies e = system.energies(integrator.coordinates(), integrator.velocities());
  const Eigen::VectorXd phi = system.constraints(integrator.time(), integrator.coordinates());
  double orthogonality = 0.0, tisserand = 0.0;
  for (int b = 0; b < system.body_count(); ++b) {
    const Eigen::Matrix3d a = system.orientation(b, integrator.coordinates());
    orthogonality = std::max(orthogonality, (a.transpose() * a - Eigen::Matrix3d::Identity()).norm());
    if (!system.model(b).rigid() && !system.model(b).floating())
      tisserand = std::max(tisserand, phi.segment<3>(system.reference_row(b) + 6).cwiseAbs().maxCoeff());
  }
  const Eigen::Index first_joint_row = system.joint_row(0);
  const double joints = phi.size() > first_joint_row ? phi.tail(phi.size() - first_joint_row).cwiseAbs().maxCoeff() : 0.0;
  Eigen::VectorXd v(8);
  v << e.kinetic, e.elastic, e.gravity, e.total(), orthogonality, tisserand, joints,
      static_cast<double>(integrator.last_iterations());
  return v;
}

// The angular momentum about the system's centre of mass [kg m²/s]: per body Σ_kl G_kl x_k × v_l = Σ_k x_k × w_k with
// w = (G ⊗ I3) v in blocks of 3 (the nodal sum Σ m_i r_i × ṙ_i through G), less M r_c × v_c; and the sum of its
// terms' magnitudes, Σ |x_k| |w_k| + |r_c| |M v_c|, the scale its round-off is relative to.
struct AngularMomentum {
  Eigen::Vector3d value;
  double terms = 0.0;
};
AngularMomentum angular_momentum(const runtime::System& system, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  Eigen::Vector3d about_origin = Eigen::Vector3d::Zero(), first_moment = Eigen::Vector3d::Zero(),
                  momentum = Eigen::Vector3d::Zero();
  double mass = 0.0, terms = 0.0;
  for (int b = 0; b < system.body_count(); ++b) {
    const runtime::BodyModel& model = system.model(b);
    // In GCMS coordinates (a floating-frame body's equivalent ones): the nodal sums through G.
    const Eigen::VectorXd q_b = runtime::gcms_coordinates(model, system.body_coordinates(q, b));
    const Eigen::VectorXd v_b = runtime::gcms_velocities(model, system.body_coordinates(q, b), system.body_coordinates(v, b));
    const Eigen::VectorXd w = runtime::mass_times(model, v_b);
    for (Eigen::Index k = 0; k < q_b.size() / 3; ++k) {
      about_origin += q_b.segment<3>(3 * k).cross(w.segment<3>(3 * k));
      terms += q_b.segment<3>(3 * k).norm() * w.segment<3>(3 * k).norm();
    }
    first_moment += runtime::mass_times(model, q_b).head<3>();  // m r_c (G's first row)
    momentum += w.head<3>();
    mass += model.mass;
  }
  const Eigen::Vector3d center = first_moment / mass;
  return {about_origin - center.cross(momentum), terms + center.norm() * momentum.norm()};
}

}  // namespace

RunSummary run_scene(Scene& scene, const std::filesystem::path& directory, const std::function<void(double)>& progress,
                     const std::function<void(const std::string&)>& warn) {
  // The integrator first: a scene whose initial state or constraints are inconsistent fails before any file.
  const std::clock_t cpu_start = std::clock();
  runtime::GeneralizedAlpha integrator(scene.system, scene.integrator);
  if (std::error_code error; !std::filesystem::create_directories(directory, error) && error)
    throw std::runtime_error(fmt::format("{}: cannot create the output directory: {}", directory.string(), error.message()));
  std::vector<std::unique_ptr<CsvFile>> files;
  RunSummary summary;
  summary.sparse = integrator.sparse();
  for (const Sensor& s : scene.sensors) {
    summary.files.push_back(directory / (s.name + ".csv"));
    files.push_back(std::make_unique<CsvFile>(summary.files.back(), columns_of(scene, s)));
  }
  std::unique_ptr<CsvFile> monitors;
  if (scene.monitors) {
    summary.files.push_back(directory / "monitors.csv");
    monitors = std::make_unique<CsvFile>(
        summary.files.back(), std::vector<std::string>{"kinetic [J]", "elastic [J]", "gravity [J]", "total [J]",
                                                        "max |A^T A - I|", "max |Tisserand| [kg m^2]",
                                                        "max |joint residual|", "Newton iterations"});
  }
  std::vector<runtime::ParaViewSeries> series;
  for (const SurfaceSeries& s : scene.paraview) {
    series.emplace_back(directory, scene.system.body_name(s.body), scene.system.model(s.body), s.stresses);
    summary.files.push_back(series.back().collection());
  }
  auto record = [&] {
    for (std::size_t k = 0; k < files.size(); ++k) files[k]->row(integrator.time(), values_of(scene, scene.sensors[k], integrator));
    if (monitors) monitors->row(integrator.time(), monitor_values(scene, integrator));
  };
  auto draw = [&] {  // each series once per time, also when called again after one of them failed
    for (std::size_t k = 0; k < series.size(); ++k)
      if (series[k].last_time() != integrator.time())
        series[k].write(integrator.time(),
                        runtime::gcms_coordinates(scene.system.model(scene.paraview[k].body),
                                                  scene.system.body_coordinates(integrator.coordinates(), scene.paraview[k].body)));
  };
  const runtime::System& system = scene.system;
  const runtime::Energies e0 = system.energies(integrator.coordinates(), integrator.velocities());
  summary.energy_initial = summary.energy_final = e0.total();
  // The drift's scale: the largest kinetic + elastic + spring energy of the run (independent of where the
  // gravity potential is zero).
  double exchanged = e0.kinetic + e0.elastic + e0.springs, largest_change = 0.0;
  // The scales that E(t) − E_0 and |L(t)| − |L_0| round relative to: the magnitudes of the terms summed in them (the
  // gravity potential depends on where its zero is; |L_0| may be round-off of a body that only translates).
  // Growth is measured against max(exchanged energy, 1e-9 of those), so round-off never warns.
  double energy_terms = std::abs(e0.gravity) + e0.kinetic + e0.elastic + e0.springs;
  double momentum_initial = 0.0, momentum_terms = 0.0;
  if (scene.conserves.angular_momentum) {
    const AngularMomentum l0 = angular_momentum(system, integrator.coordinates(), integrator.velocities());
    momentum_initial = l0.value.norm();
    momentum_terms = l0.terms;
  }
  constexpr double kRoundOffScale = 1e-9;
  bool energy_warned = false, momentum_warned = false;
  // Energies, residuals and momenta at a checked step; a conservation law broken beyond kConservationTolerance is
  // reported once, when it first happens.
  auto check = [&] {
    const Eigen::VectorXd& q = integrator.coordinates();
    const Eigen::VectorXd& v = integrator.velocities();
    const double t = integrator.time();
    summary.max_constraint_residual =
        std::max(summary.max_constraint_residual, system.constraints(t, q).cwiseAbs().maxCoeff());
    const runtime::Energies e = system.energies(q, v);
    exchanged = std::max(exchanged, e.kinetic + e.elastic + e.springs);
    largest_change = std::max(largest_change, std::abs(e.total() - summary.energy_initial));
    summary.energy_final = e.total();
    if (scene.conserves.energy) {
      energy_terms = std::max(energy_terms, std::abs(e.gravity) + e.kinetic + e.elastic + e.springs);
      const double growth =
          (e.total() - summary.energy_initial) / std::max({exchanged, kRoundOffScale * energy_terms, 1e-300});
      summary.energy_growth = std::max(summary.energy_growth, growth);  // the largest ratio tested, as warned
      if (!energy_warned && growth > kConservationTolerance) {
        energy_warned = true;
        ++summary.conservation_warnings;
        summary.warnings.push_back(fmt::format(
            "t = {:.6g} s: the energy of this conservative scene (no damping, no driven joint, no applied load) grew by "
            "{:.3g} % of its largest kinetic + elastic + spring energy (warning above {:.3g} %); generalized-alpha only "
            "dissipates, so the motion is not to be trusted: try a smaller step or a smaller rho_inf",
            t, 100.0 * growth, 100.0 * kConservationTolerance));
        if (warn) warn(summary.warnings.back());
      }
    }
    if (scene.conserves.angular_momentum) {
      const AngularMomentum l = angular_momentum(system, q, v);
      momentum_terms = std::max(momentum_terms, l.terms);
      const double growth = (l.value.norm() - momentum_initial) /
                            std::max({momentum_initial, kRoundOffScale * momentum_terms, 1e-300});
      summary.angular_momentum_growth = std::max(summary.angular_momentum_growth, growth);
      if (!momentum_warned && growth > kConservationTolerance) {
        momentum_warned = true;
        ++summary.conservation_warnings;
        summary.warnings.push_back(fmt::format(
            "t = {:.6g} s: the angular momentum about the centre of mass of this free, torque-free scene grew by "
            "{:.3g} % of its initial {:.6g} kg m^2/s (warning above {:.3g} %): the motion is not to be trusted; try a "
            "smaller step or a smaller rho_inf", t, 100.0 * growth, momentum_initial, 100.0 * kConservationTolerance));
        if (warn) warn(summary.warnings.back());
      }
    }
  };
  record();
  draw();
  // Whole steps, the last one shortened to end on the end time exactly (step_count; at most kMostSteps, scene.cpp).
  const long steps = static_cast<long>(step_count(scene.end_time, scene.integrator.step));
  bool written = true, drawn = true;
  const auto wall_start = std::chrono::steady_clock::now();
  std::chrono::steady_clock::duration in_integrator{};
  try {
    for (long k = 1; k <= steps; ++k) {
      const auto step_start = std::chrono::steady_clock::now();
      if (k < steps) integrator.step();
      else integrator.step_to(scene.end_time);
      in_integrator += std::chrono::steady_clock::now() - step_start;
      for (std::size_t w = summary.validity_warnings; w < integrator.warnings().size(); ++w) {  // the model's validity
        summary.warnings.push_back(integrator.warnings()[w]);
        ++summary.validity_warnings;
        if (warn) warn(summary.warnings.back());
      }
      written = drawn = false;
      ++summary.steps;
      summary.newton_iterations += integrator.last_iterations();
      if (k % kCheckEvery == 0 || k == steps) check();
      if (k % scene.output_every == 0 || k == steps) {
        record();
        written = true;
      }
      if (k % scene.paraview_every == 0 || k == steps) {
        draw();
        drawn = true;
      }
      if (progress && k % 100 == 0) progress(integrator.time());
    }
  } catch (...) {
    // The last completed step, whatever output_every says; a failure to write it must not hide why the run
    // stopped (the exception being handled), so it is dropped here.
    try {
      if (!written) record();
    } catch (const std::exception&) {
    }
    try {
      if (!drawn) draw();
    } catch (const std::exception&) {
    }
    summary.cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    throw;
  }
  summary.cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  summary.newton_matrices = integrator.factorizations();
  summary.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  summary.integrator_wall_seconds = std::chrono::duration<double>(in_integrator).count();
  summary.energy_drift = largest_change / std::max(exchanged, 1e-300);
  return summary;
}

}  // namespace flexbody::fbsim
