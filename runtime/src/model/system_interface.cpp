// The installed System: each member forwards to its Impl (system_impl.hpp), so that the bodies' work storage and the
// evaluation's helpers stay out of the installed header.
#include "system_impl.hpp"

#include <utility>

namespace flexbody::runtime {

System::System() : impl_(std::make_unique<Impl>()) {}
System::~System() = default;
System::System(const System& other) : impl_(std::make_unique<Impl>(*other.impl_)) {}
System& System::operator=(const System& other) {
  if (this != &other) impl_ = std::make_unique<Impl>(*other.impl_);
  return *this;
}
System::System(System&&) noexcept = default;
System& System::operator=(System&&) noexcept = default;

int System::add_body(const std::string& name, BodyModel model, const BodyState& initial) {
  return impl_->add_body(name, std::move(model), initial);
}
void System::add_joint(Joint joint) { impl_->add_joint(std::move(joint)); }
void System::add_force(PointForce force) { impl_->add_force(std::move(force)); }
void System::add_torque(PointTorque torque) { impl_->add_torque(std::move(torque)); }
void System::add_spring(SpringDamper spring) { impl_->add_spring(std::move(spring)); }
void System::set_gravity(const Eigen::Vector3d& gravity) { impl_->set_gravity(gravity); }
int System::body_count() const { return impl_->body_count(); }
const BodyModel& System::model(int body) const { return impl_->model(body); }
const std::string& System::body_name(int body) const { return impl_->body_name(body); }
int System::body_index(const std::string& name) const { return impl_->body_index(name); }
Eigen::Index System::offset(int body) const { return impl_->offset(body); }
const std::vector<Joint>& System::joints() const { return impl_->joints(); }
const std::vector<PointForce>& System::forces() const { return impl_->forces(); }
const std::vector<PointTorque>& System::torques() const { return impl_->torques(); }
const std::vector<SpringDamper>& System::springs() const { return impl_->springs(); }
Eigen::Index System::coordinate_count() const { return impl_->coordinate_count(); }
Eigen::Index System::constraint_count() const { return impl_->constraint_count(); }
Eigen::VectorXd System::initial_coordinates() const { return impl_->initial_coordinates(); }
Eigen::VectorXd System::initial_body_coordinates(int body) const { return impl_->initial_body_coordinates(body); }
void System::set_initial_coordinates(const Eigen::VectorXd& q) { impl_->set_initial_coordinates(q); }
Eigen::VectorXd System::initial_velocities() const { return impl_->initial_velocities(); }
Eigen::VectorXd System::body_coordinates(const Eigen::VectorXd& q, int body) const {
  return impl_->body_coordinates(q, body);
}
Eigen::MatrixXd System::mass_matrix(const Eigen::VectorXd& q) const { return impl_->mass_matrix(q); }
Eigen::SparseMatrix<double> System::sparse_mass_matrix(const Eigen::VectorXd& q) const {
  return impl_->sparse_mass_matrix(q);
}
Eigen::VectorXd System::mass_product(const Eigen::VectorXd& q, const Eigen::VectorXd& x) const {
  return impl_->mass_product(q, x);
}
Eigen::VectorXd System::forces(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  return impl_->forces(t, q, v);
}
void System::dynamic_residual(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& qdd,
                              Eigen::VectorXd& out, bool with_prestress) const {
  impl_->dynamic_residual(t, q, v, qdd, out, with_prestress);
}
Eigen::MatrixXd System::stiffness(const Eigen::VectorXd& q) const { return impl_->stiffness(q); }
FfrfTangent System::floating_frame_tangent(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                           const Eigen::VectorXd& a) const {
  return impl_->floating_frame_tangent(body, q, v, a);
}
Eigen::Matrix3d System::orientation(int body, const Eigen::VectorXd& q) const { return impl_->orientation(body, q); }
Eigen::Vector3d System::angular_velocity(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  return impl_->angular_velocity(body, q, v);
}
std::vector<SpringTangent> System::spring_tangents(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  return impl_->spring_tangents(q, v);
}
Eigen::VectorXd System::constraints(double t, const Eigen::VectorXd& q) const { return impl_->constraints(t, q); }
void System::constraints(double t, const Eigen::VectorXd& q, Eigen::VectorXd& phi) const {
  impl_->constraints(t, q, phi);
}
Eigen::MatrixXd System::constraint_jacobian(double t, const Eigen::VectorXd& q) const {
  return impl_->constraint_jacobian(t, q);
}
void System::sparse_constraint_jacobian(double t, const Eigen::VectorXd& q, Eigen::SparseMatrix<double>& out) const {
  impl_->sparse_constraint_jacobian(t, q, out);
}
Eigen::VectorXd System::constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q,
                                                              const Eigen::VectorXd& mu) const {
  return impl_->constraint_jacobian_transpose_product(t, q, mu);
}
void System::add_constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                                                       Eigen::VectorXd& out) const {
  impl_->add_constraint_jacobian_transpose_product(t, q, mu, out);
}
Eigen::VectorXd System::constraint_jacobian_product(double t, const Eigen::VectorXd& q,
                                                    const Eigen::VectorXd& v) const {
  return impl_->constraint_jacobian_product(t, q, v);
}
void System::constraints_and_rates(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, Eigen::VectorXd& phi,
                                   Eigen::VectorXd& rate) const {
  impl_->constraints_and_rates(t, q, v, phi, rate);
}
Eigen::VectorXd System::constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale) const {
  return impl_->constraint_time_derivative(t, q, time_scale);
}
void System::add_constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale,
                                            Eigen::VectorXd& out) const {
  impl_->add_constraint_time_derivative(t, q, time_scale, out);
}
Eigen::MatrixXd System::constraint_hessian(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& lambda) const {
  return impl_->constraint_hessian(t, q, lambda);
}
void System::add_joint_hessian(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& lambda,
                               const std::vector<Eigen::Index>& offsets, const std::vector<Eigen::Index>& counts,
                               Eigen::MatrixXd& out) const {
  impl_->add_joint_hessian(t, q, lambda, offsets, counts, out);
}
Eigen::Index System::first_redundant_constraint(double t, const Eigen::VectorXd& q) const {
  return impl_->first_redundant_constraint(t, q);
}
std::vector<RemovedConstraint> System::remove_redundant_constraints(double t, const Eigen::VectorXd& q) {
  return impl_->remove_redundant_constraints(t, q);
}
std::string System::constraint_name(Eigen::Index row) const { return impl_->constraint_name(row); }
JointReaction System::joint_reaction(std::size_t joint, double t, const Eigen::VectorXd& q,
                                     const Eigen::VectorXd& lambda) const {
  return impl_->joint_reaction(joint, t, q, lambda);
}
Eigen::Index System::joint_row(std::size_t joint) const { return impl_->joint_row(joint); }
Eigen::Index System::reference_row(int body) const { return impl_->reference_row(body); }
Energies System::energies(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const { return impl_->energies(q, v); }
bool System::has_prestress() const { return impl_->has_prestress(); }
void System::set_prestress(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& lambda,
                           double lambda_scale) const {
  impl_->set_prestress(t, q, v, lambda, lambda_scale);
}
void System::add_prestress_residual(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                    const Eigen::VectorXd& mu, double scale, Eigen::VectorXd& residual) const {
  impl_->add_prestress_residual(t, q, v, mu, scale, residual);
}
std::string System::prestress_gap(int body) const { return impl_->prestress_gap(body); }
const Eigen::VectorXd& System::prestress_weights(int body) const { return impl_->prestress_weights(body); }

}  // namespace flexbody::runtime
