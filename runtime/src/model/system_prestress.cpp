// system_prestress.cpp: the System's geometric stiffening (prestress.hpp; formulations.md, "Geometric
// Stiffening"): the weights λ of each prestressed body's cases from its spin and the loads at its interfaces, and the
// forces they add.
#include "system_impl.hpp"

#include "../kernels/outer_sum.hpp"
#include "joint_rows.hpp"

#include "flexbody/runtime/ffrf_dynamics.hpp"

#include <Eigen/Geometry>

#include <stdexcept>
#include <string>

namespace flexbody::runtime {

std::string System::Impl::prestress_gap(int body) const {
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  if (!b.model.prestress) return "it has no geometric stiffness";
  const Prestress& p = *b.model.prestress;
  for (std::size_t c = 0; c < 6; ++c)  // a file may hold a subset of the cases (SCHEMA.md)
    if (p.centrifugal[c] < 0)
      return std::string("its body file lacks the case centrifugal:") + format::kCentrifugalCases[c] +
             ", so its spin's prestress is incomplete";
  auto elsewhere = [&](const Marker& m) { return m.body == body && m.interface < 0; };
  auto incomplete = [&](const Marker& m) {  // at an interface whose six cases are not all in the file
    if (m.body != body || m.interface < 0) return false;
    for (int k : p.interface_cases[static_cast<std::size_t>(m.interface)])
      if (k < 0) return true;
    return false;
  };
  auto missing = [](const std::string& what, const Marker& m) {
    return what + " acts on it at " + m.name + ", which is not an interface, so its prestress leaves that load out";
  };
  auto lacking = [](const std::string& what, const Marker& m) {
    return what + " acts on it at " + m.name + ", whose six load cases its body file does not all hold";
  };
  for (const Joint& j : joints_) {
    if (elsewhere(j.first) || elsewhere(j.second)) return missing("joint '" + j.name + "'", elsewhere(j.first) ? j.first : j.second);
    if (incomplete(j.first) || incomplete(j.second)) return lacking("joint '" + j.name + "'", incomplete(j.first) ? j.first : j.second);
  }
  for (const PointForce& f : forces_) {
    if (elsewhere(f.marker)) return missing("a force", f.marker);
    if (incomplete(f.marker)) return lacking("a force", f.marker);
  }
  for (const PointTorque& t : torques_) {
    if (elsewhere(t.marker)) return missing("a torque", t.marker);
    if (incomplete(t.marker)) return lacking("a torque", t.marker);
  }
  for (const SpringDamper& s : springs_) {
    if (elsewhere(s.first) || elsewhere(s.second))
      return missing("spring '" + s.name + "'", elsewhere(s.first) ? s.first : s.second);
    if (incomplete(s.first) || incomplete(s.second))
      return lacking("spring '" + s.name + "'", incomplete(s.first) ? s.first : s.second);
  }
  return {};
}

void System::Impl::set_prestress(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                 const Eigen::VectorXd& lambda, double lambda_scale) const {
  update_prestress(t, q, v, lambda, lambda_scale, true);
}

void System::Impl::add_prestress_residual(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                          const Eigen::VectorXd& mu, double scale, Eigen::VectorXd& residual) const {
  if (!has_prestress()) return;
  update_prestress(t, q, v, mu, scale, false);
  for (const Body& b : bodies_)
    if (b.prestress.active) add_prestress_forces(b, q, residual.segment(b.offset, b.model.coordinate_count()), -1.0 / scale);
}

void System::Impl::update_prestress(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                    const Eigen::VectorXd& lambda, double lambda_scale, bool evaluate_joints) const {
  if (!has_prestress()) return;
  if (lambda.size() != 0 && lambda.size() != constraint_count())
    throw std::invalid_argument("set_prestress: " + std::to_string(lambda.size()) + " multipliers for " +
                                std::to_string(constraint_count()) + " constraint rows (all rows, or none)");
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    const Body& b = bodies_[i];
    if (!b.model.prestress) continue;
    for (InterfaceLoad& l : b.prestress.loads) l = InterfaceLoad{};
    b.prestress.orientation = orientation(static_cast<int>(i), q);  // the loads go to body axes
  }
  auto add_force = [&](const Marker& m, const Eigen::Vector3d& force) {  // world axes, at marker m
    PrestressState& state = bodies_[static_cast<std::size_t>(m.body)].prestress;
    state.loads[static_cast<std::size_t>(m.interface)].force += state.orientation.transpose() * force;
  };
  auto loaded = [&](const Marker& m) {  // a marker at an interface of a prestressed body
    return m.body != kGround && m.interface >= 0 && bodies_[static_cast<std::size_t>(m.body)].model.prestress != nullptr;
  };
  // The joints' reactions: the generalized force −Φ_qᵀ λ of each joint on each of its bodies.
  if (lambda.size() != 0) {
    for (std::size_t k = 0; k < joints_.size(); ++k) {
      const Joint& j = joints_[k];
      if (!loaded(j.first) && !loaded(j.second)) continue;
      JointEvaluation& e = joint_work_[k];  // Φ_qᵀ λ per side, matrix-free (joint_rows.hpp)
      if (evaluate_joints)
        detail::joint_transpose_product(j, t, body_view(q, j.first.body), body_view(q, j.second.body),
                                        lambda.segment(joint_row(k), j.rows()), e.product_first, e.product_second);
      for (int side = 0; side < 2; ++side) {
        const Marker& m = side == 0 ? j.first : j.second;
        if (!loaded(m)) continue;
        const Body& b = bodies_[static_cast<std::size_t>(m.body)];
        b.prestress.generalized.noalias() = -lambda_scale * (side == 0 ? e.product_first : e.product_second);
        const VectorRef q_b = body_view(q, m.body);
        const JointReaction w = wrench(b, q_b, b.prestress.generalized, marker_position(m, q_b));
        InterfaceLoad& load = b.prestress.loads[static_cast<std::size_t>(m.interface)];
        load.force += b.prestress.orientation.transpose() * w.force;
        load.moment += b.prestress.orientation.transpose() * w.moment;
      }
    }
  }
  for (const PointForce& p : forces_)
    if (loaded(p.marker)) add_force(p.marker, p.force(t));
  for (const PointTorque& p : torques_) {
    if (!loaded(p.marker)) continue;
    PrestressState& state = bodies_[static_cast<std::size_t>(p.marker.body)].prestress;
    state.loads[static_cast<std::size_t>(p.marker.interface)].moment += state.orientation.transpose() * p.torque(t);
  }
  for (std::size_t k = 0; k < springs_.size(); ++k) {
    const SpringDamper& s = springs_[k];
    if (!loaded(s.first) && !loaded(s.second)) continue;
    const Eigen::Vector3d force = spring_force(k, q, v);  // on the first marker
    if (loaded(s.first)) add_force(s.first, force);
    if (loaded(s.second)) add_force(s.second, -force);
  }
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    const Body& b = bodies_[i];
    if (!b.model.prestress) continue;
    const int body = static_cast<int>(i);
    PrestressState& state = b.prestress;
    const Eigen::Vector3d omega_bar = state.orientation.transpose() * angular_velocity(body, q, v);
    runtime::prestress_weights(*b.model.prestress, omega_bar, state.loads, state.weights);
    state.active = !state.weights.isZero(0.0);
    state.packed.noalias() = state.packed_cases * state.weights;  // Σ λ_k of the used block's lower triangle
    const Eigen::Index n = state.matrix.rows();
    for (Eigen::Index c = 0, e = 0; c < n; ++c)
      for (Eigen::Index r = c; r < n; ++r, ++e) state.matrix(r, c) = state.matrix(c, r) = state.packed(e);
  }
}

void System::Impl::add_prestress_forces(const Body& b, const Eigen::VectorXd& q, Eigen::Ref<Eigen::VectorXd> f_b,
                                        double sign) const {
  PrestressState& state = b.prestress;
  if (!state.active) return;
  const Eigen::Index n = b.model.coordinate_count();
  const auto q_b = q.segment(b.offset, n);
  if (b.model.floating()) {  // K_g η on the modal rows
    const Eigen::Index n_m = b.model.modes;
    state.forces.noalias() = state.matrix * q_b.tail(n_m);
    f_b.tail(n_m) -= sign * state.forces;
    return;
  }
  // ½ ξ̄ᵀ (K_g ⊗ I3) ξ̄ with K_g the weighted field block: with Ξ̄ = Aᵀ Ξ (3 x n_f) its body-frame forces are
  // H = Ξ̄ K_g, and ∂/∂ξ = A H, ∂/∂A = Ξ Hᵀ (Eqs. 86-87 with K_g ⊗ I3 for K̂).
  const Eigen::Index n_f = b.model.field_count();
  const Eigen::Matrix3d a = orientation_of(q_b);
  const Eigen::Map<const Eigen::Matrix3Xd> xi(q_b.data() + 12, 3, n_f);
  state.xi_bar.resize(3 * n_f);
  state.forces.resize(3 * n_f);
  Eigen::Map<Eigen::Matrix3Xd> xi_bar(state.xi_bar.data(), 3, n_f), h(state.forces.data(), 3, n_f);
  xi_bar.noalias() = a.transpose() * xi;
  h.noalias() = xi_bar * state.matrix;
  const Eigen::Matrix3d grad_a = detail::outer_sum(xi, Eigen::Map<const Eigen::Matrix3Xd>(state.forces.data(), 3, n_f));
  f_b.segment<9>(3) -= sign * Eigen::Map<const Eigen::Matrix<double, 9, 1>>(grad_a.data());
  for (Eigen::Index f = 0; f < n_f; ++f) f_b.segment<3>(12 + 3 * f) -= sign * (a * h.col(f));
}

}  // namespace flexbody::runtime
