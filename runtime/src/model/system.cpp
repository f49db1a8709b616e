#include "flexbody/runtime/system.hpp"

#include "../body/gcms_elastic_padded.hpp"
#include "../kernels/outer_sum.hpp"
#include "../kernels/parallel.hpp"
#include "joint_rows.hpp"

#include "flexbody/runtime/gcms_elastic.hpp"
#include "flexbody/runtime/reference_constraints.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace flexbody::runtime {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

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

// E(p) = [−e, [e]× + e0 I] (3 x 4): ω = 2 E(p) ṗ is the global angular velocity, and ṗ = ½ E(p)ᵀ ω for unit p.
Eigen::Matrix<double, 3, 4> euler_global_velocity_matrix(const Eigen::Vector4d& p) {
  Eigen::Matrix<double, 3, 4> e;
  e.col(0) = -p.tail<3>();
  e.rightCols<3>() = skew(p.tail<3>()) + p(0) * Eigen::Matrix3d::Identity();
  return e;
}

}  // namespace

void System::check_marker(const Marker& m, const std::string& what) const {
  if (m.body == kGround) return;
  if (m.body < 0 || m.body >= body_count())
    throw std::invalid_argument(what + ": marker " + m.name + " is not on a body of this system");
  const BodyModel& model = bodies_[static_cast<std::size_t>(m.body)].model;
  if (m.y.size() != 4 + model.field_count() || m.rotation.cols() != 3 * model.field_count())
    throw std::invalid_argument(what + ": marker " + m.name + " was made for another number of modes of body '" +
                                bodies_[static_cast<std::size_t>(m.body)].name + "'");
  if (m.floating != model.floating() || (m.floating && m.modal_displacement.cols() != model.modes))
    throw std::invalid_argument(what + ": marker " + m.name + " was made for another formulation of body '" +
                                bodies_[static_cast<std::size_t>(m.body)].name + "'");
  // An interface marker books its loads on that interface's prestress cases: it must be this body's interface.
  if (m.interface >= 0 && (m.interface >= static_cast<int>(model.interfaces.size()) ||
                           m.y != model.interfaces[static_cast<std::size_t>(m.interface)].y_row))
    throw std::invalid_argument(what + ": marker " + m.name + " names interface " + std::to_string(m.interface) +
                                " of body '" + bodies_[static_cast<std::size_t>(m.body)].name + "', which it is not");
}

int System::add_body(const std::string& name, BodyModel model, const BodyState& initial) {
  for (const Body& b : bodies_)
    if (b.name == name) throw std::invalid_argument("body '" + name + "' is defined twice");
  const Eigen::Index n_xi = 3 * model.field_count();
  BodyState state = initial;
  if (model.floating()) {
    const Eigen::Index n_m = model.floating_frame->modes;
    if (n_m != model.modes)
      throw std::invalid_argument("body '" + name + "': its floating frame has " + std::to_string(n_m) + " modes, the body " +
                                  std::to_string(model.modes));
    if (state.eta.size() == 0) state.eta = Eigen::VectorXd::Zero(n_m);
    if (state.eta_dot.size() == 0) state.eta_dot = Eigen::VectorXd::Zero(n_m);
    if (state.eta.size() != n_m || state.eta_dot.size() != n_m)
      throw std::invalid_argument("body '" + name + "': eta and eta_dot need n_m = " + std::to_string(n_m) + " entries");
    if (state.xi.size() > 0 || state.xi_dot.size() > 0)
      throw std::invalid_argument("body '" + name + "': a floating-frame body starts from eta, not from xi");
  }
  if (state.xi.size() == 0) state.xi = Eigen::VectorXd::Zero(n_xi);
  if (state.xi_dot.size() == 0) state.xi_dot = Eigen::VectorXd::Zero(n_xi);
  if (state.xi.size() != n_xi || state.xi_dot.size() != n_xi)
    throw std::invalid_argument("body '" + name + "': xi and xi_dot need 3 n_f = " + std::to_string(n_xi) + " entries");
  const Eigen::MatrixXd& d = model.damping;
  if (model.sparse && d.size() > 0)
    throw std::invalid_argument("body '" + name + "': the full-order reference body takes no damping");
  if (!model.sparse && (model.stiffness.rows() != n_xi || model.stiffness.cols() != n_xi))
    throw std::invalid_argument("body '" + name + "': K_hat must be 3 n_f square (" + std::to_string(n_xi) + ")");
  if (d.size() > 0 && (d.rows() != n_xi || d.cols() != n_xi))
    throw std::invalid_argument("body '" + name + "': the damping matrix must be 3 n_f square (" + std::to_string(n_xi) + ")");
  if (model.unit_field_mass && !model.sparse) {  // the short mass product reads neither G_ff nor G[4:, 0:4]
    const Eigen::Index n_f = model.field_count();
    const Eigen::MatrixXd& g = model.mass_matrix;
    if (g.rows() != 4 + n_f || g.cols() != 4 + n_f || g.bottomRightCorner(n_f, n_f) != Eigen::MatrixXd::Identity(n_f, n_f) ||
        g.bottomLeftCorner(n_f, 4) != g.topRightCorner(4, n_f).transpose())
      throw std::invalid_argument("body '" + name + "': unit_field_mass is set, but G_ff is not exactly I or G is not "
                                  "symmetric (make_body_model sets it only where both hold)");
  }
  if ((state.orientation.transpose() * state.orientation - Eigen::Matrix3d::Identity()).norm() > 1e-12 ||
      state.orientation.determinant() < 0.0)
    throw std::invalid_argument("body '" + name + "': the initial orientation is not a rotation (A^T A = I, det A = 1)");
  const Eigen::Index rows = model.floating() ? 1 : model.rigid() ? 6 : (model.needs_translational_tisserand() ? 12 : 9);
  std::shared_ptr<const detail::PaddedMatrix> stiffness;
  if (!shared_matrices_.ptr) shared_matrices_.ptr = std::make_shared<detail::SharedMatrices>();
  if (!model.sparse && !model.rigid() && !model.floating())  // copies of one part share one K̂
    stiffness = std::make_shared<const detail::PaddedMatrix>(shared_matrices_.ptr->get(model.stiffness));
  PrestressState prestress;
  if (model.prestress) {
    const Prestress& p = *model.prestress;
    const auto cases = static_cast<Eigen::Index>(p.cases.size());
    const Eigen::Index size = 4 + model.field_count();
    for (const Eigen::MatrixXd& g : p.matrices)
      if (g.rows() != size || g.cols() != size)
        throw std::invalid_argument("body '" + name + "': its prestress matrices must be 4 + n_f = " +
                                    std::to_string(size) + " square");
    if (p.matrices.size() != p.cases.size() || p.interface_cases.size() != model.interfaces.size() ||
        (model.floating() && model.floating_frame->prestress.size() != p.cases.size()))
      throw std::invalid_argument("body '" + name + "': its prestress cases do not match its matrices, interfaces or "
                                  "floating frame");
    prestress.weights = Eigen::VectorXd::Zero(cases);
    // The block the forces use (a GCMS body's field block, a floating frame's modal matrices), its lower triangle
    // packed column by column, one column per case: the weighted sum is one product over a third of the entries at
    // 18 fields (the sum over the whole (4 + n_f)² matrices took as long as the body's elastic forces).
    const std::vector<Eigen::MatrixXd>& used = model.floating() ? model.floating_frame->prestress : p.matrices;
    const Eigen::Index n = model.floating() ? model.modes : model.field_count(), skip = model.floating() ? 0 : 4;
    prestress.packed_cases.resize(n * (n + 1) / 2, cases);
    for (Eigen::Index k = 0; k < cases; ++k)
      for (Eigen::Index c = 0, e = 0; c < n; ++c)
        for (Eigen::Index r = c; r < n; ++r) prestress.packed_cases(e++, k) = used[static_cast<std::size_t>(k)](skip + r, skip + c);
    prestress.matrix.setZero(n, n);
    prestress.loads.assign(model.interfaces.size(), InterfaceLoad{});
    prestress.generalized.resize(model.coordinate_count());
    ++prestressed_bodies_;
  }
  bodies_.push_back({name, std::move(model), state, coordinates_, rows, reference_total_, std::move(stiffness), {}, {},
                     std::move(prestress)});
  coordinates_ += bodies_.back().model.coordinate_count();
  reference_total_ += rows;
  return static_cast<int>(bodies_.size()) - 1;
}

void System::add_joint(Joint joint) {
  check_marker(joint.first, "joint '" + joint.name + "'");
  check_marker(joint.second, "joint '" + joint.name + "'");
  for (const Joint& j : joints_)
    if (j.name == joint.name) throw std::invalid_argument("joint '" + joint.name + "' is defined twice");
  joint_start_.push_back(joint_total_);
  joint_total_ += joint.rows();
  joints_.push_back(std::move(joint));
  joint_work_.emplace_back();
}

void System::add_force(PointForce force) {
  if (force.marker.body < 0 || force.marker.body >= body_count())
    throw std::invalid_argument("point force at " + force.marker.name + ": not a marker on a body of this system");
  if (!force.force) throw std::invalid_argument("point force at " + force.marker.name + ": no force function");
  check_marker(force.marker, "point force");
  forces_.push_back(std::move(force));
}

void System::add_torque(PointTorque torque) {
  if (torque.marker.body < 0 || torque.marker.body >= body_count())
    throw std::invalid_argument("torque at " + torque.marker.name + ": not a marker on a body of this system");
  if (!torque.torque) throw std::invalid_argument("torque at " + torque.marker.name + ": no torque function");
  check_marker(torque.marker, "torque");
  torques_.push_back(std::move(torque));
}

void System::add_spring(SpringDamper spring) {
  for (const Marker* m : {&spring.first, &spring.second})
    if (m->body < kGround || m->body >= body_count())
      throw std::invalid_argument("spring '" + spring.name + "': marker " + m->name + " is not in this system");
  check_marker(spring.first, "spring '" + spring.name + "'");
  check_marker(spring.second, "spring '" + spring.name + "'");
  if (!(spring.stiffness >= 0.0) || !(spring.damping >= 0.0) || !(spring.rest_length >= 0.0))
    throw std::invalid_argument("spring '" + spring.name + "': stiffness, damping and length must be >= 0");
  springs_.push_back(std::move(spring));
  spring_work_.emplace_back();
}

int System::body_index(const std::string& name) const {
  for (std::size_t b = 0; b < bodies_.size(); ++b)
    if (bodies_[b].name == name) return static_cast<int>(b);
  throw std::invalid_argument("no body '" + name + "'");
}

Eigen::Index System::constraint_count() const { return reference_total_ + joint_total_; }

Eigen::VectorXd System::initial_coordinates() const {
  Eigen::VectorXd q(coordinates_);
  for (const Body& b : bodies_) {
    q.segment<3>(b.offset) = b.initial.position;
    if (b.model.floating()) {
      q.segment<4>(b.offset + 3) = euler_parameters(b.initial.orientation);
      q.segment(b.offset + 7, b.model.modes) = b.initial.eta;
      continue;
    }
    q.segment<9>(b.offset + 3) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(b.initial.orientation.data());
    q.segment(b.offset + 12, b.initial.xi.size()) = b.initial.xi;
  }
  return q;
}

void System::set_initial_coordinates(const Eigen::VectorXd& q) {
  if (q.size() != coordinates_) throw std::invalid_argument("set_initial_coordinates: q has the wrong size");
  for (int k = 0; k < body_count(); ++k) {  // every body checked before any is changed
    const Eigen::Matrix3d a = orientation(k, q);
    if (!((a.transpose() * a - Eigen::Matrix3d::Identity()).norm() <= 1e-9))
      throw std::invalid_argument("body '" + body_name(k) + "': the new initial orientation is not a rotation");
  }
  for (int k = 0; k < body_count(); ++k) {
    Body& b = bodies_[static_cast<std::size_t>(k)];
    const Eigen::Matrix3d a = orientation(k, q);
    b.initial.position = q.segment<3>(b.offset);
    b.initial.orientation = a;
    if (b.model.floating())
      b.initial.eta = q.segment(b.offset + 7, b.model.modes);
    else
      b.initial.xi = q.segment(b.offset + 12, 3 * b.model.field_count());
  }
}

Eigen::VectorXd System::initial_velocities() const {
  Eigen::VectorXd v(coordinates_);
  for (const Body& b : bodies_) {
    v.segment<3>(b.offset) = b.initial.velocity;
    if (b.model.floating()) {
      const Eigen::Vector4d p = euler_parameters(b.initial.orientation);
      v.segment<4>(b.offset + 3) = 0.5 * euler_global_velocity_matrix(p).transpose() * b.initial.angular_velocity;
      v.segment(b.offset + 7, b.model.modes) = b.initial.eta_dot;
      continue;
    }
    const Eigen::Matrix3d a_dot = skew(b.initial.angular_velocity) * b.initial.orientation;
    v.segment<9>(b.offset + 3) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(a_dot.data());
    v.segment(b.offset + 12, b.initial.xi_dot.size()) = b.initial.xi_dot;
  }
  return v;
}

VectorRef System::body_view(const Eigen::VectorXd& q, int body) const {
  if (body == kGround) return q.head(0);
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  return q.segment(b.offset, b.model.coordinate_count());
}

Eigen::VectorXd System::body_coordinates(const Eigen::VectorXd& q, int body) const {
  if (body == kGround) return {};
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  return q.segment(b.offset, b.model.coordinate_count());
}

Eigen::MatrixXd System::mass_matrix(const Eigen::VectorXd& q) const {
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

Eigen::SparseMatrix<double> System::sparse_mass_matrix(const Eigen::VectorXd& q) const {
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

Eigen::VectorXd System::mass_product(const Eigen::VectorXd& q, const Eigen::VectorXd& x) const {
  Eigen::VectorXd y(coordinates_);
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    y.segment(b.offset, n) = b.model.floating()
                                 ? ffrf_mass_product(*b.model.floating_frame, q.segment(b.offset, n), x.segment(b.offset, n))
                                 : mass_times(b.model, x.segment(b.offset, n));
  }
  return y;
}

Eigen::VectorXd System::forces(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
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

void System::dynamic_residual(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& qdd,
                              Eigen::VectorXd& out, bool with_prestress) const {
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

void System::add_body_forces(const Body& b, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
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

void System::add_applied_forces(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, double sign,
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

Eigen::Vector3d System::spring_force(std::size_t k, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
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

FfrfTangent System::floating_frame_tangent(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                           const Eigen::VectorXd& a) const {
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  if (!b.model.floating()) throw std::invalid_argument("body '" + b.name + "' has no floating frame");
  const Eigen::Index n = b.model.coordinate_count();
  FfrfTangent t = ffrf_tangent(*b.model.floating_frame, q.segment(b.offset, n), v.segment(b.offset, n),
                               a.segment(b.offset, n), gravity_);
  if (b.prestress.active) t.stiffness.bottomRightCorner(b.model.modes, b.model.modes) += b.prestress.matrix;
  return t;
}

Eigen::Matrix3d System::orientation(int body, const Eigen::VectorXd& q) const {
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  return b.model.floating() ? euler_rotation(q.segment<4>(b.offset + 3)) : orientation_of(q.segment(b.offset, 12));
}

Eigen::Vector3d System::angular_velocity(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  if (b.model.floating()) return 2.0 * euler_global_velocity_matrix(q.segment<4>(b.offset + 3)) * v.segment<4>(b.offset + 3);
  const Eigen::Matrix3d w = orientation_of(v.segment(b.offset, 12)) * orientation_of(q.segment(b.offset, 12)).transpose();
  return 0.5 * Eigen::Vector3d(w(2, 1) - w(1, 2), w(0, 2) - w(2, 0), w(1, 0) - w(0, 1));
}

Eigen::MatrixXd System::stiffness(const Eigen::VectorXd& q) const {
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

std::vector<SpringTangent> System::spring_tangents(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
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

Eigen::Index System::reference_residuals(const Eigen::VectorXd& q, Eigen::VectorXd& phi) const {
  Eigen::Index row = 0;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    const auto q_b = q.segment(b.offset, n);
    if (b.model.floating()) {  // pᵀp − 1
      phi(row++) = q_b.segment<4>(3).squaredNorm() - 1.0;
      continue;
    }
    const Eigen::Matrix<double, 9, 1> ref = reference_residual(b.model.tisserand, orientation_of(q_b), q_b.tail(n - 12));
    phi.segment(row, std::min<Eigen::Index>(9, reference_rows(b))) = ref.head(std::min<Eigen::Index>(9, reference_rows(b)));
    if (reference_rows(b) == 12) {  // Eq. 77: Σ_f G[0, 4 + f] ξ_f
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (Eigen::Index f = 0; f < b.model.field_count(); ++f) sum += b.model.g_border(0, 4 + f) * q_b.segment<3>(12 + 3 * f);
      phi.segment<3>(row + 9) = sum;
    }
    row += reference_rows(b);
  }
  return row;
}

Eigen::Index System::reference_rates(const Eigen::VectorXd& q, const Eigen::VectorXd& v, Eigen::VectorXd& rate) const {
  Eigen::Index row = 0;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count(), rows = std::min<Eigen::Index>(9, reference_rows(b));
    const auto q_b = q.segment(b.offset, n), v_b = v.segment(b.offset, n);
    if (b.model.floating()) {  // 2 pᵀṗ
      rate(row++) = 2.0 * q_b.segment<4>(3).dot(v_b.segment<4>(3));
      continue;
    }
    rate.segment(row, rows) = reference_jacobian_product(b.model.tisserand, orientation_of(q_b), q_b.tail(n - 12),
                                                         orientation_of(v_b), v_b.tail(n - 12))
                                  .head(rows);
    if (reference_rows(b) == 12) {
      rate.segment<3>(row + 9).setZero();
      for (Eigen::Index f = 0; f < b.model.field_count(); ++f)
        rate.segment<3>(row + 9) += b.model.g_border(0, 4 + f) * v_b.segment<3>(12 + 3 * f);
    }
    row += reference_rows(b);
  }
  return row;
}

const JointEvaluation& System::evaluated(std::size_t k, double t, const Eigen::VectorXd& q) const {
  const Joint& j = joints_[k];
  evaluate_joint(j, t, body_view(q, j.first.body), body_view(q, j.second.body), joint_work_[k]);
  return joint_work_[k];
}

Eigen::VectorXd System::constraints(double t, const Eigen::VectorXd& q) const {
  Eigen::VectorXd phi;
  constraints(t, q, phi);
  return phi;
}

void System::constraints(double t, const Eigen::VectorXd& q, Eigen::VectorXd& phi) const {
  phi.resize(constraint_count());
  reference_residuals(q, phi);
  // Each joint into its own rows, without its Jacobian (joint_rows.hpp).
  detail::for_each(static_cast<int>(joints_.size()), [&](int k) {
    const Joint& j = joints_[static_cast<std::size_t>(k)];
    detail::joint_residual(j, t, body_view(q, j.first.body), body_view(q, j.second.body),
                           phi.segment(joint_row(static_cast<std::size_t>(k)), j.rows()));
  });
}

void System::constraints_and_rates(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, Eigen::VectorXd& phi,
                                   Eigen::VectorXd& rate) const {
  phi.resize(constraint_count());
  rate.resize(constraint_count());
  reference_residuals(q, phi);
  reference_rates(q, v, rate);
  // Each joint evaluated once for both, into its own rows, without its Jacobian (joint_rows.hpp).
  detail::for_each(static_cast<int>(joints_.size()), [&](int k) {
    const Joint& j = joints_[static_cast<std::size_t>(k)];
    const Eigen::Index row = joint_row(static_cast<std::size_t>(k));
    detail::joint_residual_and_rate(j, t, body_view(q, j.first.body), body_view(q, j.second.body),
                                    body_view(v, j.first.body), body_view(v, j.second.body), phi.segment(row, j.rows()),
                                    rate.segment(row, j.rows()));
  });
}

Eigen::MatrixXd System::constraint_jacobian(double t, const Eigen::VectorXd& q) const {
  Eigen::SparseMatrix<double> jac;
  sparse_constraint_jacobian(t, q, jac);
  return Eigen::MatrixXd(jac);
}

Eigen::VectorXd System::constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q,
                                                              const Eigen::VectorXd& mu) const {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(coordinates_);
  add_constraint_jacobian_transpose_product(t, q, mu, out);
  return out;
}

void System::add_constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                                                       Eigen::VectorXd& out) const {
  Eigen::Index row = 0;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count(), rows = std::min<Eigen::Index>(9, reference_rows(b));
    const auto q_b = q.segment(b.offset, n);
    if (b.model.floating()) {
      out.segment<4>(b.offset + 3) += 2.0 * mu(row++) * q_b.segment<4>(3);
      continue;
    }
    Eigen::Matrix<double, 9, 1> mu_b = Eigen::Matrix<double, 9, 1>::Zero();
    mu_b.head(rows) = mu.segment(row, rows);
    b.gcms.reference.resize(n - 3);
    reference_jacobian_transpose_product(b.model.tisserand, orientation_of(q_b), q_b.tail(n - 12), mu_b, b.gcms.reference);
    out.segment(b.offset + 3, n - 3) += b.gcms.reference;
    if (reference_rows(b) == 12)
      for (Eigen::Index f = 0; f < b.model.field_count(); ++f)
        out.segment<3>(b.offset + 12 + 3 * f) += b.model.g_border(0, 4 + f) * mu.segment<3>(row + 9);
    row += reference_rows(b);
  }
  // Each joint's Φ_qᵀ μ without its Jacobian (joint_rows.hpp), into its own storage in parallel; the sums in joint
  // order, so that the result is the same for any thread count.
  const auto count = static_cast<int>(joints_.size());
  detail::for_each(count, [&](int k) {
    const auto ks = static_cast<std::size_t>(k);
    const Joint& j = joints_[ks];
    JointEvaluation& e = joint_work_[ks];
    detail::joint_transpose_product(j, t, body_view(q, j.first.body), body_view(q, j.second.body),
                                    mu.segment(joint_row(ks), j.rows()), e.product_first, e.product_second);
  });
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const Joint& j = joints_[k];
    const JointEvaluation& e = joint_work_[k];
    if (j.first.body != kGround) out.segment(offset(j.first.body), e.product_first.size()) += e.product_first;
    if (j.second.body != kGround) out.segment(offset(j.second.body), e.product_second.size()) += e.product_second;
  }
}

Eigen::VectorXd System::constraint_jacobian_product(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  Eigen::VectorXd phi, rate;
  constraints_and_rates(t, q, v, phi, rate);
  return rate;
}

Eigen::VectorXd System::constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale) const {
  Eigen::VectorXd rate = Eigen::VectorXd::Zero(constraint_count());
  add_constraint_time_derivative(t, q, time_scale, rate);
  return rate;
}

void System::add_constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale,
                                            Eigen::VectorXd& out) const {
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const Joint& j = joints_[k];
    // The type's last row, the angle, is the only one that depends on t (never removed: remove_redundant_constraints).
    if (j.type != JointType::driven_revolute) continue;
    out(joint_row(k) + j.rows() - 1) += driven_row_time_derivative(j, t, time_scale, body_view(q, j.first.body),
                                                                   body_view(q, j.second.body), joint_work_[k].frames);
  }
}

Eigen::MatrixXd System::constraint_hessian(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& lambda) const {
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(coordinates_, coordinates_);
  Eigen::Index row = 0;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    const auto q_b = q.segment(b.offset, n);
    if (b.model.floating()) {  // ∂²(pᵀp)/∂p² = 2 I
      h.block<4, 4>(b.offset + 3, b.offset + 3).diagonal().setConstant(2.0 * lambda(row++));
      continue;
    }
    Eigen::Matrix<double, 9, 1> l = Eigen::Matrix<double, 9, 1>::Zero();
    l.head(std::min<Eigen::Index>(9, reference_rows(b))) = lambda.segment(row, std::min<Eigen::Index>(9, reference_rows(b)));
    h.block(b.offset + 3, b.offset + 3, n - 3, n - 3) =
        reference_hessian(b.model.tisserand, orientation_of(q_b), q_b.tail(n - 12), l);
    row += reference_rows(b);
  }
  std::vector<Eigen::Index> offsets, counts;
  for (const Body& b : bodies_) {
    offsets.push_back(b.offset);
    counts.push_back(b.model.coordinate_count());
  }
  add_joint_hessian(t, q, lambda, offsets, counts, h);
  return h;
}

void System::add_joint_hessian(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& lambda,
                               const std::vector<Eigen::Index>& offsets, const std::vector<Eigen::Index>& counts,
                               Eigen::MatrixXd& out) const {
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const Joint& j = joints_[k];
    if (j.rows() == 0) continue;  // every row removed as redundant
    const Eigen::VectorXd l = lambda.segment(joint_row(k), j.rows());
    if (!(l.cwiseAbs().maxCoeff() > 0.0)) continue;
    // A spherical joint between GCMS bodies (or ground) has rows linear in q: no curvature.
    if (j.type == JointType::spherical && !j.first.floating && !j.second.floating) continue;
    const int body[2] = {j.first.body, j.second.body};
    Eigen::VectorXd q_of[2];
    for (int s = 0; s < 2; ++s)
      if (body[s] != kGround) q_of[s] = body_coordinates(q, body[s]);
    // Φ_jᵀ λ on each side, over the kept coordinates.
    auto gradient = [&](Eigen::VectorXd (&g)[2]) {
      const JointEvaluation e = evaluate_joint(j, t, q_of[0], q_of[1]);
      for (int s = 0; s < 2; ++s)
        if (body[s] != kGround) g[s] = (s == 0 ? e.jacobian_first : e.jacobian_second).transpose() * l;
    };
    for (int s = 0; s < 2; ++s) {
      if (body[s] == kGround) continue;
      const auto bs = static_cast<std::size_t>(body[s]);
      for (Eigen::Index c = 0; c < counts[bs]; ++c) {
        const double x = q_of[s](c), step = 1e-6 * (1.0 + std::abs(x));
        Eigen::VectorXd plus[2], minus[2];
        q_of[s](c) = x + step;
        gradient(plus);
        q_of[s](c) = x - step;
        gradient(minus);
        q_of[s](c) = x;
        for (int r = 0; r < 2; ++r) {
          if (body[r] == kGround) continue;
          const auto br = static_cast<std::size_t>(body[r]);
          const Eigen::Index n = counts[br];
          out.block(offsets[br], offsets[bs] + c, n, 1) += (plus[r].head(n) - minus[r].head(n)) / (2.0 * step);
        }
      }
    }
  }
}

std::string System::constraint_name(Eigen::Index row) const {
  for (const Body& b : bodies_) {
    if (b.model.floating()) {
      if (row < 1) return "body '" + b.name + "': normalisation of the Euler parameters";
      row -= 1;
      continue;
    }
    if (row < 6) return "body '" + b.name + "': orthogonality of A (Eq. 79)";
    if (row < 9 && row < reference_rows(b)) return "body '" + b.name + "': rotational Tisserand condition (Eq. 78)";
    if (row < reference_rows(b)) return "body '" + b.name + "': translational Tisserand condition (Eq. 77)";
    row -= reference_rows(b);
  }
  for (const Joint& j : joints_) {
    if (row < j.rows()) return "joint '" + j.name + "'";
    row -= j.rows();
  }
  return "constraint " + std::to_string(row);
}

Eigen::Index System::reference_row(int body) const {
  return body == body_count() ? reference_total_ : bodies_.at(static_cast<std::size_t>(body)).reference_row;
}

Eigen::Index System::joint_row(std::size_t joint) const {
  return reference_total_ + (joint == joints_.size() ? joint_total_ : joint_start_.at(joint));
}

JointReaction System::joint_reaction(std::size_t joint, double t, const Eigen::VectorXd& q,
                                    const Eigen::VectorXd& lambda) const {
  const Joint& j = joints_.at(joint);
  if (j.first.body == kGround)
    throw std::invalid_argument("joint '" + j.name + "': its reaction is reported on the first marker's body, which is ground");
  const Eigen::VectorXd q1 = body_coordinates(q, j.first.body);
  const JointEvaluation e = evaluate_joint(j, t, q1, body_coordinates(q, j.second.body));
  const Eigen::VectorXd generalized = -e.jacobian_first.transpose() * lambda.segment(joint_row(joint), j.rows());
  return wrench(bodies_[static_cast<std::size_t>(j.first.body)], q1, generalized, marker_position(j.first, q1));
}

JointReaction System::wrench(const Body& b, const VectorRef& q_b, const Eigen::VectorXd& g,
                             const Eigen::Vector3d& point) {
  JointReaction w;
  w.force = g.head<3>();
  // The moment about τ: the virtual work of a rigid rotation δθ of the whole body.
  Eigen::Vector3d about_tau = Eigen::Vector3d::Zero();
  if (b.model.floating()) {  // δp = ½ E(p)ᵀ δθ, η unchanged by a rigid rotation
    about_tau = 0.5 * euler_global_velocity_matrix(q_b.segment<4>(3)) * g.segment<4>(3);
  } else {
    for (Eigen::Index k = 1; k < q_b.size() / 3; ++k)  // the columns a_j of A, then the fields ξ_f: 3-blocks after τ
      about_tau += q_b.segment<3>(3 * k).cross(g.segment<3>(3 * k));
  }
  w.moment = about_tau - (point - q_b.head<3>()).cross(w.force);
  return w;
}

Energies System::energies(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  Energies e;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    const auto q_b = q.segment(b.offset, n);
    const auto v_b = v.segment(b.offset, n);
    if (b.model.floating()) {  // gravity: −g · (m τ + A S(η)), the deformed centre of mass
      const FfrfModel& ff = *b.model.floating_frame;
      e.kinetic += ffrf_kinetic_energy(ff, q_b, v_b);
      e.elastic += ffrf_elastic_energy(ff, q_b);
      e.gravity -= gravity_.dot(ff.mass * q_b.head<3>() + euler_rotation(q_b.segment<4>(3)) * ffrf_first_moment(ff, q_b));
      continue;
    }
    e.kinetic += 0.5 * v_b.dot(mass_times(b.model, v_b));  // T = ½ v_bᵀ (G ⊗ I3) v_b
    for (Eigen::Index k = 0; k < n / 3; ++k) e.gravity -= b.model.g_border(0, k) * gravity_.dot(q_b.segment<3>(3 * k));
    if (!b.model.rigid()) e.elastic += body_elastic_forces(b.model, orientation_of(q_b), q_b.tail(n - 12)).energy;
  }
  for (const SpringDamper& s : springs_) {
    const double stretch = (marker_position(s.second, body_coordinates(q, s.second.body)) -
                            marker_position(s.first, body_coordinates(q, s.first.body))).norm() - s.rest_length;
    e.springs += 0.5 * s.stiffness * stretch * stretch;
  }
  return e;
}

}  // namespace flexbody::runtime
