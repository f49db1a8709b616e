// System: adding bodies, joints, forces and springs, and the scene's coordinates (initial_assembly.cpp closes its
// joints; system_dynamics.cpp evaluates masses and forces, system_constraints.cpp the constraint rows,
// system_outputs.cpp what a run reports).
#include "system_impl.hpp"

#include "../kernels/dense_product.hpp"
#include "../kernels/rotation.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

namespace flexbody::runtime {

using detail::euler_global_velocity_matrix;
using detail::skew;

void System::Impl::check_marker(const Marker& m, const std::string& what) const {
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

int System::Impl::add_body(const std::string& name, BodyModel model, const BodyState& initial) {
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

void System::Impl::add_joint(Joint joint) {
  check_marker(joint.first, "joint '" + joint.name + "'");
  check_marker(joint.second, "joint '" + joint.name + "'");
  for (const Joint& j : joints_)
    if (j.name == joint.name) throw std::invalid_argument("joint '" + joint.name + "' is defined twice");
  joint_start_.push_back(joint_total_);
  joint_total_ += joint.rows();
  joints_.push_back(std::move(joint));
  joint_work_.emplace_back();
}

void System::Impl::add_force(PointForce force) {
  if (force.marker.body < 0 || force.marker.body >= body_count())
    throw std::invalid_argument("point force at " + force.marker.name + ": not a marker on a body of this system");
  if (!force.force) throw std::invalid_argument("point force at " + force.marker.name + ": no force function");
  check_marker(force.marker, "point force");
  forces_.push_back(std::move(force));
}

void System::Impl::add_torque(PointTorque torque) {
  if (torque.marker.body < 0 || torque.marker.body >= body_count())
    throw std::invalid_argument("torque at " + torque.marker.name + ": not a marker on a body of this system");
  if (!torque.torque) throw std::invalid_argument("torque at " + torque.marker.name + ": no torque function");
  check_marker(torque.marker, "torque");
  torques_.push_back(std::move(torque));
}

void System::Impl::add_spring(SpringDamper spring) {
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

int System::Impl::body_index(const std::string& name) const {
  for (std::size_t b = 0; b < bodies_.size(); ++b)
    if (bodies_[b].name == name) return static_cast<int>(b);
  throw std::invalid_argument("no body '" + name + "'");
}

Eigen::Index System::Impl::constraint_count() const { return reference_total_ + joint_total_; }

Eigen::VectorXd System::Impl::initial_coordinates() const {
  Eigen::VectorXd q(coordinates_);
  for (int k = 0; k < body_count(); ++k) {
    const Body& b = bodies_[static_cast<std::size_t>(k)];
    q.segment(b.offset, b.model.coordinate_count()) = initial_body_coordinates(k);
  }
  return q;
}

Eigen::VectorXd System::Impl::initial_body_coordinates(int body) const {
  if (body == kGround) return {};
  if (body < 0 || body >= body_count())
    throw std::invalid_argument("initial_body_coordinates: no body " + std::to_string(body) + " in the system");
  const Body& b = bodies_[static_cast<std::size_t>(body)];
  Eigen::VectorXd q = Eigen::VectorXd::Zero(b.model.coordinate_count());
  q.head<3>() = b.initial.position;
  if (b.model.floating()) {
    q.segment<4>(3) = euler_parameters(b.initial.orientation);
    q.segment(7, b.initial.eta.size()) = b.initial.eta;
    return q;
  }
  q.segment<9>(3) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(b.initial.orientation.data());
  q.segment(12, b.initial.xi.size()) = b.initial.xi;
  return q;
}

void System::Impl::set_initial_coordinates(const Eigen::VectorXd& q) {
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

Eigen::VectorXd System::Impl::initial_velocities() const {
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

VectorRef System::Impl::body_view(const Eigen::VectorXd& q, int body) const {
  if (body == kGround) return q.head(0);
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  return q.segment(b.offset, b.model.coordinate_count());
}

Eigen::VectorXd System::Impl::body_coordinates(const Eigen::VectorXd& q, int body) const {
  if (body == kGround) return {};
  const Body& b = bodies_.at(static_cast<std::size_t>(body));
  return q.segment(b.offset, b.model.coordinate_count());
}

}  // namespace flexbody::runtime
