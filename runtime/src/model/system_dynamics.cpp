// System: the mass matrix, the forces and their tangents, body by body (the residual of the equations of motion,
// Eq. (40) and its FFRF and rigid counterparts, before the constraint rows of system_constraints.cpp).
#include "system_impl.hpp"

#include "../body/gcms_elastic_padded.hpp"
#include "../kernels/outer_sum.hpp"
#include "../kernels/parallel.hpp"
#include "../kernels/rotation.hpp"

#include "flexbody/runtime/gcms_elastic.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <stdexcept>

namespace flexbody::runtime {
namespace {

using detail::euler_global_velocity_matrix;
using detail::skew;

// Adds ∂r/∂q_bᵀ F to the body's block of f: (y ⊗ I3) F on a GCMS body.
void add_marker_force(Eigen::Ref<Eigen::VectorXd> f_b, const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& force) {
  if (m.floating) {  // ∂r/∂qᵀ F = [F; (∂(A ū_c)/∂p)ᵀ F; Ψ_cᵀ Aᵀ F], marker_position_jacobian's blocks
    const Eigen::Index n = q_b.size() - 7;
    const Eigen::Vector4d p = q_b.segment<4>(3);
    const Eigen::Vector3d local = m.y.segment<3>(1) + m.modal_displacement * q_b.tail(n);
    const Eigen::Vector3d body_force = euler_rotation(p).transpose() * force;
    f_b.head<3>() += force;
    f_b.segment<4>(3).noalias() += euler_rotation_derivative(p, local).transpose() * force;
    f_b.tail(n).noalias() += m.modal_displacement.transpose() * body_force;
    return;
  }
  for (Eigen::Index k = 0; k < m.y.size(); ++k) f_b.segment<3>(3 * k) += m.y(k) * force;
}

}  // namespace

Eigen::MatrixXd System::Impl::mass_matrix(const Eigen::VectorXd& q) const {
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(coordinates_, coordinates_);
  for (const Body& b : bodies_) {
    if (b.model.floating()) {
      const Eigen::Index n = b.model.coordinate_count();
      const VectorRef q_b = q.segment(b.offset, n);
      for (Eigen::Index c = 0; c < n; ++c)  // M_b(q) column by column: M_b e_c
        m.block(b.offset, b.offset + c, n, 1) = ffrf_mass_product(*b.model.floating_frame, q_b, Eigen::VectorXd::Unit(n, c));
      continue;
    }
    const Eigen::Index columns = 4 + b.model.field_count();
    Eigen::MatrixXd g = b.model.sparse ? Eigen::MatrixXd::Zero(columns, columns) : b.model.mass_matrix;
    if (b.model.sparse) {  // G = [border; border_fᵀ M_s]
      g.topRows<4>() = b.model.sparse->border;
      g.bottomLeftCorner(columns - 4, 4) = b.model.sparse->border.rightCols(columns - 4).transpose();
      g.bottomRightCorner(columns - 4, columns - 4) = Eigen::MatrixXd(b.model.sparse->mass);
    }
    for (Eigen::Index r = 0; r < columns; ++r)  // M_b = G ⊗ I3 (Eq. 66)
      for (Eigen::Index c = 0; c < columns; ++c) m.block<3, 3>(b.offset + 3 * r, b.offset + 3 * c).diagonal().setConstant(g(r, c));
  }
  return m;
}

Eigen::SparseMatrix<double> System::Impl::sparse_mass_matrix(const Eigen::VectorXd& q) const {
  std::vector<Eigen::Triplet<double>> entries;
  auto add = [&entries](Eigen::Index offset, Eigen::Index r, Eigen::Index c, double value) {
    if (value != 0.0)
      for (int d = 0; d < 3; ++d) entries.emplace_back(offset + 3 * r + d, offset + 3 * c + d, value);
  };
  for (const Body& b : bodies_) {
    const BodyModel& model = b.model;
    if (model.floating()) {  // M_b(q), dense (7 + n_m square)
      const Eigen::Index n = model.coordinate_count();
      const VectorRef q_b = q.segment(b.offset, n);
      for (Eigen::Index c = 0; c < n; ++c) {
        const Eigen::VectorXd column = ffrf_mass_product(*model.floating_frame, q_b, Eigen::VectorXd::Unit(n, c));
        for (Eigen::Index r = 0; r < n; ++r)
          if (column(r) != 0.0) entries.emplace_back(b.offset + r, b.offset + c, column(r));
      }
      continue;
    }
    const Eigen::Index columns = 4 + model.field_count();
    if (!model.sparse) {
      for (Eigen::Index r = 0; r < columns; ++r)
        for (Eigen::Index c = 0; c < columns; ++c) add(b.offset, r, c, model.mass_matrix(r, c));
      continue;
    }
    for (int r = 0; r < 4; ++r)
      for (Eigen::Index c = 0; c < columns; ++c) {
        add(b.offset, r, c, model.sparse->border(r, c));
        if (c >= 4) add(b.offset, c, r, model.sparse->border(r, c));
      }
    const Eigen::SparseMatrix<double>& m_s = model.sparse->mass;
    for (Eigen::Index k = 0; k < m_s.outerSize(); ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(m_s, k); it; ++it) add(b.offset, 4 + it.row(), 4 + it.col(), it.value());
  }
  Eigen::SparseMatrix<double> m(coordinates_, coordinates_);
  m.setFromTriplets(entries.begin(), entries.end());
  return m;
}

Eigen::VectorXd System::Impl::mass_product(const Eigen::VectorXd& q, const Eigen::VectorXd& x) const {
  Eigen::VectorXd y(coordinates_);
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    y.segment(b.offset, n) = b.model.floating()
                                 ? ffrf_mass_product(*b.model.floating_frame, q.segment(b.offset, n), x.segment(b.offset, n))
                                 : mass_times(b.model, x.segment(b.offset, n));
  }
  return y;
}

Eigen::VectorXd System::Impl::forces(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(coordinates_);
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    auto f_b = f.segment(b.offset, n);
    if (b.model.floating()) {  // gravity, the quadratic velocity vector, elastic and damping forces
      f_b = ffrf_forces(*b.model.floating_frame, q.segment(b.offset, n), v.segment(b.offset, n), gravity_);
      add_prestress_forces(b, q, f_b, 1.0);
      continue;
    }
    add_body_forces(b, q, v, f_b);
  }
  add_applied_forces(t, q, v, 1.0, f);
  return f;
}

void System::Impl::dynamic_residual(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                    const Eigen::VectorXd& qdd, Eigen::VectorXd& out, bool with_prestress) const {
  out.resize(coordinates_);
  const int count = body_count();
  // Each body writes its own slice from its own workspace (detail::kParallelFrom).
  detail::for_each(count, [&](int k) {
    const Body& b = bodies_[static_cast<std::size_t>(k)];
    const Eigen::Index n = b.model.coordinate_count();
    auto out_b = out.segment(b.offset, n);
    if (b.model.floating()) {  // R(q, q̇, q̈) in one pass over the invariants
      ffrf_residual(*b.model.floating_frame, q.segment(b.offset, n), v.segment(b.offset, n), qdd.segment(b.offset, n),
                    gravity_, b.work, out_b);
      if (with_prestress) add_prestress_forces(b, q, out_b, -1.0);
      return;
    }
    mass_times(b.model, qdd.segment(b.offset, n), out_b);
    out_b = -out_b;
    add_body_forces(b, q, v, out_b, with_prestress);
    out_b = -out_b;
  });
  add_applied_forces(t, q, v, -1.0, out);
}

void System::Impl::add_body_forces(const Body& b, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                   Eigen::Ref<Eigen::VectorXd> f_b, bool with_prestress) const {
  const Eigen::Index n = b.model.coordinate_count();
  {
    for (Eigen::Index k = 0; k < n / 3; ++k) f_b.segment<3>(3 * k) += b.model.g_border(0, k) * gravity_;  // (G[:, 0] ⊗ I3) g
    if (!b.model.rigid()) {
      const auto q_b = q.segment(b.offset, n);
      GcmsWorkspace& w = b.gcms;
      if (b.stiffness) {
        detail::elastic_forces(*b.stiffness, orientation_of(q_b), q_b.tail(n - 12), w.elastic, w.xi_bar);
      } else {
        w.elastic = body_elastic_forces(b.model, orientation_of(q_b), q_b.tail(n - 12));
      }
      const ElasticForces& elastic = w.elastic;
      f_b.segment<9>(3) -= elastic.grad_a;   // Eq. 86
      f_b.tail(n - 12) -= elastic.grad_xi;   // Eq. 87
      if (with_prestress) add_prestress_forces(b, q, f_b, 1.0);
      const bool sparse_damping = b.model.sparse && b.model.sparse->stiffness_damping > 0.0;
      if (b.model.damping.size() > 0 || sparse_damping) {  // R = ½ ξ̄̇ᵀ D̂ ξ̄̇, ξ̄̇_f = Ȧᵀ ξ_f + Aᵀ ξ̇_f
        const auto v_b = v.segment(b.offset, n);
        const auto xi = q_b.tail(n - 12);
        const auto xi_dot = v_b.tail(n - 12);
        const Eigen::Matrix3d a = orientation_of(q_b), a_dot = orientation_of(v_b);
        const Eigen::Index n_f = (n - 12) / 3;
        w.rate.resize(n - 12);
        w.damping_force.resize(n - 12);
        for (Eigen::Index i = 0; i < n_f; ++i)
          w.rate.segment<3>(3 * i) = a_dot.transpose() * xi.segment<3>(3 * i) + a.transpose() * xi_dot.segment<3>(3 * i);
        if (sparse_damping)
          w.damping_force = b.model.sparse->stiffness_damping * (b.model.sparse->stiffness * w.rate);
        else
          w.damping_force.noalias() = b.model.damping * w.rate;
        // Dᵀ y with D = ∂ξ̄/∂a (gcms_elastic.hpp) is Σ_f ξ_f y_fᵀ, vectorised.
        const Eigen::Matrix3d d_t_y = detail::outer_sum(Eigen::Map<const Eigen::Matrix3Xd>(xi.data(), 3, n_f),
                                                        Eigen::Map<const Eigen::Matrix3Xd>(w.damping_force.data(), 3, n_f));
        f_b.segment<9>(3) -= Eigen::Map<const Eigen::Matrix<double, 9, 1>>(d_t_y.data());
        for (Eigen::Index i = 0; i < n_f; ++i) f_b.segment<3>(12 + 3 * i) -= a * w.damping_force.segment<3>(3 * i);
      }
    }
  }
}

void System::Impl::add_applied_forces(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, double sign,
                                      Eigen::VectorXd& f) const {
  for (const PointForce& p : forces_) {
    const Body& b = bodies_.at(static_cast<std::size_t>(p.marker.body));
    const Eigen::Index n = b.model.coordinate_count();
    add_marker_force(f.segment(b.offset, n), p.marker, q.segment(b.offset, n), sign * p.force(t));
  }
  for (const PointTorque& p : torques_) {
    const Body& b = bodies_.at(static_cast<std::size_t>(p.marker.body));
    const Eigen::Index n = b.model.coordinate_count();
    const Eigen::Vector3d torque = sign * p.torque(t);
    if (b.model.floating()) {  // δφ = A (2 Ḡ δp + Θ_c δη): Q_p = 2 Ḡᵀ Aᵀ T, Q_η = Θ_cᵀ Aᵀ T
      const Eigen::Vector4d e = q.segment<4>(b.offset + 3);
      const Eigen::Vector3d body_torque = euler_rotation(e).transpose() * torque;
      f.segment<4>(b.offset + 3) += 2.0 * euler_body_velocity_matrix(e).transpose() * body_torque;
      f.segment(b.offset + 7, n - 7).noalias() += p.marker.modal_rotation.transpose() * body_torque;
      continue;
    }
    const Eigen::Matrix3d a = orientation_of(q.segment(b.offset, n));
    const Eigen::Matrix3d q_a = 0.5 * skew(torque) * a;  // tr(Q_Aᵀ [δθ]× A) = T·δθ for orthogonal A
    f.segment<9>(b.offset + 3) += Eigen::Map<const Eigen::Matrix<double, 9, 1>>(q_a.data());
    if (n > 12) {  // δθ = A R Âᵀ δξ through the marker's small rotation: Q_ξf = A R_fᵀ Aᵀ T
      // (and through ξ̄ = Âᵀ ξ also on A: Q_a += Dᵀ Rᵀ Aᵀ T).
      const Eigen::Vector3d body_torque = a.transpose() * torque;
      const Eigen::Index n_f = (n - 12) / 3;
      const auto xi = q.segment(b.offset + 12, n - 12);
      Eigen::Matrix3d d_t_q = Eigen::Matrix3d::Zero();  // Dᵀ q̄ = Σ_f ξ_f q̄_fᵀ, q̄_f = R_fᵀ Aᵀ T
      for (Eigen::Index i = 0; i < n_f; ++i) {
        const Eigen::Vector3d q_bar = p.marker.rotation.middleCols<3>(3 * i).transpose() * body_torque;
        f.segment<3>(b.offset + 12 + 3 * i) += a * q_bar;
        d_t_q.noalias() += xi.segment<3>(3 * i) * q_bar.transpose();
      }
      f.segment<9>(b.offset + 3) += Eigen::Map<const Eigen::Matrix<double, 9, 1>>(d_t_q.data());
    }
  }
  for (std::size_t k = 0; k < springs_.size(); ++k) {
    const SpringDamper& s = springs_[k];
    const Eigen::Vector3d force = sign * spring_force(k, q, v);
    if (s.first.body != kGround)
      add_marker_force(f.segment(offset(s.first.body), model(s.first.body).coordinate_count()), s.first,
                       body_view(q, s.first.body), force);
    if (s.second.body != kGround)
      add_marker_force(f.segment(offset(s.second.body), model(s.second.body).coordinate_count()), s.second,
                       body_view(q, s.second.body), -force);
  }
}

Eigen::Vector3d System::Impl::spring_force(std::size_t k, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  const SpringDamper& s = springs_[k];
  std::array<Eigen::MatrixXd, 2>& work = spring_work_[k];  // one per marker: their bodies' sizes differ
  const VectorRef q1 = body_view(q, s.first.body), q2 = body_view(q, s.second.body);
  const VectorRef v1 = body_view(v, s.first.body), v2 = body_view(v, s.second.body);
  const Eigen::Vector3d d = marker_position(s.second, q2) - marker_position(s.first, q1);
  const double length = d.norm();
  if (!(length > 0.0)) return Eigen::Vector3d::Zero();  // coincident markers: no direction, no force
  const Eigen::Vector3d e = d / length;
  Eigen::Vector3d rate = Eigen::Vector3d::Zero();  // ṙ_2 − ṙ_1
  if (s.second.body != kGround) {
    marker_position_jacobian(s.second, q2, work[1]);
    rate.noalias() += work[1] * v2;
  }
  if (s.first.body != kGround) {
    marker_position_jacobian(s.first, q1, work[0]);
    rate.noalias() -= work[0] * v1;
  }
  return (s.stiffness * (length - s.rest_length) + s.damping * e.dot(rate)) * e;
}

FfrfTangent System::Impl::floating_frame_tangent(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                                 const Eigen::VectorXd& a) const {
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  if (!b.model.floating()) throw std::invalid_argument("body '" + b.name + "' has no floating frame");
  const Eigen::Index n = b.model.coordinate_count();
  FfrfTangent t = ffrf_tangent(*b.model.floating_frame, q.segment(b.offset, n), v.segment(b.offset, n),
                               a.segment(b.offset, n), gravity_);
  if (b.prestress.active) t.stiffness.bottomRightCorner(b.model.modes, b.model.modes) += b.prestress.matrix;
  return t;
}

Eigen::Matrix3d System::Impl::orientation(int body, const Eigen::VectorXd& q) const {
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  return b.model.floating() ? euler_rotation(q.segment<4>(b.offset + 3)) : orientation_of(q.segment(b.offset, 12));
}

Eigen::Vector3d System::Impl::angular_velocity(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  if (b.model.floating()) return 2.0 * euler_global_velocity_matrix(q.segment<4>(b.offset + 3)) * v.segment<4>(b.offset + 3);
  const Eigen::Matrix3d w = orientation_of(v.segment(b.offset, 12)) * orientation_of(q.segment(b.offset, 12)).transpose();
  return 0.5 * Eigen::Vector3d(w(2, 1) - w(1, 2), w(0, 2) - w(2, 0), w(1, 0) - w(0, 1));
}

Eigen::MatrixXd System::Impl::stiffness(const Eigen::VectorXd& q) const {
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(coordinates_, coordinates_);
  for (const Body& b : bodies_) {
    if (b.model.rigid() || b.model.floating()) continue;
    const Eigen::Index n = b.model.coordinate_count(), n_xi = n - 12;
    const auto q_b = q.segment(b.offset, n);
    ElasticTangent t = body_elastic_tangent(b.model, orientation_of(q_b), q_b.tail(n_xi), true);
    if (b.prestress.active) {  // ½ ξ̄ᵀ (K_g ⊗ I3) ξ̄ has the Hessian of the elastic energy with K_g ⊗ I3 for K̂
      const Eigen::Index n_f = n_xi / 3;
      Eigen::MatrixXd k_g = Eigen::MatrixXd::Zero(n_xi, n_xi);
      for (Eigen::Index f = 0; f < n_f; ++f)
        for (Eigen::Index c = 0; c < n_f; ++c)
          k_g.block<3, 3>(3 * f, 3 * c).diagonal().setConstant(b.prestress.matrix(f, c));
      const ElasticTangent geometric = elastic_tangent(k_g, orientation_of(q_b), q_b.tail(n_xi), true);
      t.aa += geometric.aa;
      t.a_xi += geometric.a_xi;
      t.xi_xi += geometric.xi_xi;
    }
    k.block<9, 9>(b.offset + 3, b.offset + 3) = t.aa;
    k.block(b.offset + 3, b.offset + 12, 9, n_xi) = t.a_xi;
    k.block(b.offset + 12, b.offset + 3, n_xi, 9) = t.a_xi.transpose();
    k.block(b.offset + 12, b.offset + 12, n_xi, n_xi) = t.xi_xi;
  }
  return k;
}

std::vector<SpringTangent> System::Impl::spring_tangents(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  std::vector<SpringTangent> tangents;
  for (const SpringDamper& s : springs_) {
    const VectorRef q1 = body_view(q, s.first.body), q2 = body_view(q, s.second.body);
    const Eigen::Vector3d d = marker_position(s.second, q2) - marker_position(s.first, q1);
    const double length = d.norm();
    if (!(length > 0.0)) continue;
    SpringTangent t;
    t.first = s.first.body;
    t.second = s.second.body;
    if (t.first != kGround) t.p_first = marker_position_jacobian(s.first, q1);
    if (t.second != kGround) t.p_second = marker_position_jacobian(s.second, q2);
    const Eigen::Vector3d e = d / length;
    Eigen::Vector3d rate = Eigen::Vector3d::Zero();
    if (t.second != kGround) rate += t.p_second * body_view(v, s.second.body);
    if (t.first != kGround) rate -= t.p_first * body_view(v, s.first.body);
    const double tension = s.stiffness * (length - s.rest_length) + s.damping * e.dot(rate);
    const Eigen::Matrix3d along = e * e.transpose();
    t.stiffness = s.stiffness * along + tension / length * (Eigen::Matrix3d::Identity() - along);
    t.damping = s.damping * along;
    tangents.push_back(std::move(t));
  }
  return tangents;
}

}  // namespace flexbody::runtime
