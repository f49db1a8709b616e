#include "output_values.hpp"

#include "flexbody/runtime/ffrf_dynamics.hpp"
#include "flexbody/runtime/gcms_elastic.hpp"
#include "flexbody/runtime/reference_constraints.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>

namespace flexbody::scene {

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

const std::vector<std::string>& monitor_columns() {
  static const std::vector<std::string> columns{"kinetic [J]", "elastic [J]", "gravity [J]", "total [J]",
                                                "max |A^T A - I|", "max |Tisserand| [kg m^2]", "max |joint residual|",
                                                "Newton iterations"};
  return columns;
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


}  // namespace flexbody::scene
