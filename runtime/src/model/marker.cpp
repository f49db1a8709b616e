#include "flexbody/runtime/marker.hpp"

#include "../kernels/rotation.hpp"

#include "flexbody/runtime/ffrf_dynamics.hpp"
#include "flexbody/runtime/gcms_elastic.hpp"

#include "marker_frame.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <stdexcept>

namespace flexbody::runtime {
namespace {

using detail::skew;

void check_coordinates(const Marker& m, const VectorRef& q_b) {
  const Eigen::Index expected = m.floating ? 7 + m.modal_displacement.cols() : 3 * m.y.size();
  if (q_b.size() != expected)
    throw std::invalid_argument("marker " + m.name + ": " + std::to_string(q_b.size()) + " body coordinates, expected " +
                                std::to_string(expected));
}

// A marker made from its GCMS row y and rotation R, given its floating-frame form when the body has one: mode m
// moves it by Ψ_c(:, m) = W_mᵀ y and turns it by Θ_c(:, m) = R c_m + (the mode's rigid rotation).
Marker finished(const BodyModel& model, Marker m) {
  if (!model.floating()) return m;
  const FfrfModel& f = *model.floating_frame;
  if (std::abs(m.y(0) - 1.0) > 1e-12)
    throw std::invalid_argument("marker " + m.name + ": its weights sum to " + std::to_string(m.y(0)) + ", not 1");
  const Eigen::Index n_f = model.field_count();
  m.floating = true;
  m.modal_displacement.resize(3, f.modes);
  m.modal_rotation.resize(3, f.modes);
  for (Eigen::Index k = 0; k < f.modes; ++k) {
    m.modal_displacement.col(k) = f.shapes.middleCols<3>(3 * k).transpose() * m.y;
    Eigen::VectorXd c(3 * n_f);
    for (Eigen::Index g = 0; g < n_f; ++g) c.segment<3>(3 * g) = f.shapes.block<1, 3>(4 + g, 3 * k).transpose();
    m.modal_rotation.col(k) = m.rotation * c + f.rigid_rotations.col(k);
  }
  return m;
}

Eigen::Vector4d euler_of(const VectorRef& q_b) { return q_b.segment<4>(3); }

Marker make_marker(int body, std::string name, Eigen::VectorXd y, Eigen::MatrixXd rotation,
                   const Eigen::Vector3d& ground_point = Eigen::Vector3d::Zero()) {
  Marker m;
  m.body = body;
  m.name = std::move(name);
  m.y = std::move(y);
  m.rotation = std::move(rotation);
  m.ground_point = ground_point;
  return m;
}

// ∂A/∂p_k of the Euler parameters' rotation (euler_rotation): D_0 = 2 (e0 I + [e]×), D_i = 2 (E_i eᵀ + e E_iᵀ − e_i I +
// e0 [E_i]×), so that euler_rotation_derivative(p, x) = [D_0 x, ..., D_3 x]; once per frame instead of per vector.
std::array<Eigen::Matrix3d, 4> euler_rotation_partials(const Eigen::Vector4d& p) {
  const double e0 = p(0);
  const Eigen::Vector3d e = p.tail<3>();
  std::array<Eigen::Matrix3d, 4> d;
  d[0] = 2.0 * (e0 * Eigen::Matrix3d::Identity() + skew(e));
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d unit = Eigen::Vector3d::Unit(i);
    d[static_cast<std::size_t>(i) + 1] =
        2.0 * (unit * e.transpose() + e * unit.transpose() - e(i) * Eigen::Matrix3d::Identity() + e0 * skew(unit));
  }
  return d;
}

}  // namespace

Marker interface_marker(const BodyModel& model, int body, const std::string& body_name, const std::string& name) {
  for (std::size_t k = 0; k < model.interfaces.size(); ++k) {
    const format::Interface& i = model.interfaces[k];
    if (i.name != name) continue;
    Marker m = finished(model, make_marker(body, body_name + "/" + name, i.y_row, i.rotation));
    m.interface = static_cast<int>(k);
    return m;
  }
  std::string known;
  for (const format::Interface& i : model.interfaces) known += (known.empty() ? "" : ", ") + i.name;
  throw std::invalid_argument(model.source + ": no interface '" + name + "' (interfaces: " +
                              (known.empty() ? std::string("none") : known) + ")");
}

Marker point_marker(const BodyModel& model, int body, const std::string& body_name, const Eigen::Vector3d& point) {
  Marker m = make_marker(body, body_name + "/point", Eigen::VectorXd::Zero(4 + model.field_count()),
                         Eigen::MatrixXd::Zero(3, 3 * model.field_count()));
  m.y(0) = 1.0;
  m.y.segment<3>(1) = point;
  return finished(model, m);
}

Marker node_marker(const BodyModel& model, int body, const std::string& body_name, Eigen::Index node) {
  if (node < 0 || node >= model.nodes.rows())
    throw std::invalid_argument(model.source + ": node " + std::to_string(node) + " does not exist (the mesh has " +
                                std::to_string(model.nodes.rows()) + " nodes)");
  Marker m = make_marker(body, body_name + "/node " + std::to_string(node), Eigen::VectorXd::Zero(4 + model.field_count()),
                         Eigen::MatrixXd::Zero(3, 3 * model.field_count()));
  m.y(0) = 1.0;
  m.y.segment<3>(1) = model.nodes.row(node).transpose();
  m.y.tail(model.field_count()) = field_row(model, node).transpose();
  return finished(model, m);
}

Marker ground_marker(const Eigen::Vector3d& point) {
  return make_marker(kGround, "ground", Eigen::VectorXd(), Eigen::MatrixXd(), point);
}

Eigen::Matrix3d marker_body_orientation(const Marker& m, const VectorRef& q_b) {
  if (m.body == kGround) return Eigen::Matrix3d::Identity();
  check_coordinates(m, q_b);
  return m.floating ? euler_rotation(euler_of(q_b)) : orientation_of(q_b);
}

Eigen::Vector3d marker_position(const Marker& m, const VectorRef& q_b) {
  if (m.body == kGround) return m.ground_point;
  check_coordinates(m, q_b);
  if (m.floating)  // τ + A(p) (X̄_c + Ψ_c η)
    return q_b.head<3>() + euler_rotation(euler_of(q_b)) * (m.y.segment<3>(1) + m.modal_displacement * q_b.tail(q_b.size() - 7));
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < m.y.size(); ++k) r += m.y(k) * q_b.segment<3>(3 * k);
  return r;
}

void marker_position_jacobian(const Marker& m, const VectorRef& q_b, Eigen::MatrixXd& jac) {
  if (m.floating) {
    check_coordinates(m, q_b);
    const Eigen::Index n = q_b.size() - 7;
    const Eigen::Vector4d p = euler_of(q_b);
    jac.resize(3, q_b.size());
    jac.leftCols<3>().setIdentity();
    const Eigen::Vector3d local = m.y.segment<3>(1) + m.modal_displacement * q_b.tail(n);
    jac.middleCols<4>(3) = euler_rotation_derivative(p, local);
    jac.rightCols(n).noalias() = euler_rotation(p) * m.modal_displacement;
    return;
  }
  jac.setZero(3, 3 * m.y.size());
  for (Eigen::Index k = 0; k < m.y.size(); ++k) jac.block<3, 3>(0, 3 * k).diagonal().setConstant(m.y(k));
}

Eigen::MatrixXd marker_position_jacobian(const Marker& m, const VectorRef& q_b) {
  Eigen::MatrixXd jac;
  marker_position_jacobian(m, q_b, jac);
  return jac;
}

void detail::MarkerFrame::evaluate_values(const Marker& m, const VectorRef& q_b) {
  marker_ = &m;
  turned_ = nullptr;
  v_ = nullptr;
  small_.setZero();
  if (m.body == kGround) {
    kind_ = Kind::ground;
    size_ = 0;
    return;
  }
  check_coordinates(m, q_b);
  size_ = q_b.size();
  q_ = q_b.data();
  if (m.floating) {
    kind_ = Kind::floating;
    euler_ = euler_of(q_b);
    rotation_ = euler_rotation(euler_);
    small_.noalias() = m.modal_rotation * q_b.tail(size_ - 7);
    local_ = m.y.segment<3>(1);
    local_.noalias() += m.modal_displacement * q_b.tail(size_ - 7);
    return;
  }
  kind_ = Kind::gcms;
  rotation_ = orientation_of(q_b);
  // R ξ̄ = Σ_f R_f Aᵀ ξ_f without forming ξ̄.
  for (Eigen::Index f = 0; f < (size_ - 12) / 3; ++f)
    small_.noalias() += m.rotation.middleCols<3>(3 * f) * (rotation_.transpose() * q_b.segment<3>(12 + 3 * f));
}

void detail::MarkerFrame::evaluate(const Marker& m, const VectorRef& q_b) { evaluate_values(m, q_b); }

void detail::MarkerFrame::evaluate(const Marker& m, const VectorRef& q_b, Eigen::MatrixXd& storage) {
  evaluate_values(m, q_b);
  if (kind_ != Kind::gcms || size_ == 12) return;
  // ∂(R ξ̄)/∂A(i, j) = Σ_f R_f(:, j) ξ_f(i) (ξ̄_f = Aᵀ ξ_f); R_f Aᵀ, which ∂u/∂ξ_f = −A [d]× R_f Aᵀ takes for every
  // direction d.
  storage.resize(3, size_ - 12);
  small_by_a_.setZero();
  for (Eigen::Index f = 0; f < (size_ - 12) / 3; ++f) {
    const Eigen::Vector3d xi_f = q_b.segment<3>(12 + 3 * f);
    const auto r_f = m.rotation.middleCols<3>(3 * f);
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) small_by_a_.col(3 * j + i) += xi_f(i) * r_f.col(j);
    storage.middleCols<3>(3 * f).noalias() = r_f * rotation_.transpose();
  }
  turned_ = &storage;
}

Eigen::Vector3d detail::MarkerFrame::position() const {
  switch (kind_) {
    case Kind::ground: return marker_->ground_point;
    case Kind::floating: return Eigen::Map<const Eigen::Vector3d>(q_) + rotation_ * local_;
    case Kind::gcms: break;
  }
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < marker_->y.size(); ++k) r += marker_->y(k) * Eigen::Map<const Eigen::Vector3d>(q_ + 3 * k);
  return r;
}

void detail::MarkerFrame::set_rates(const VectorRef& v_b) {
  if (kind_ == Kind::ground) return;
  if (v_b.size() != size_)
    throw std::invalid_argument("marker " + marker_->name + ": " + std::to_string(v_b.size()) + " body velocities, expected " +
                                std::to_string(size_));
  v_ = v_b.data();
  if (kind_ == Kind::floating) {  // dA/dt = Σ_k ∂A/∂p_k ṗ_k, d(Θ_c η)/dt
    const std::array<Eigen::Matrix3d, 4> d = euler_rotation_partials(euler_);
    rotation_rate_ = d[0] * v_b(3) + d[1] * v_b(4) + d[2] * v_b(5) + d[3] * v_b(6);
    small_rate_.noalias() = marker_->modal_rotation * v_b.tail(size_ - 7);
    return;
  }
  // d(Σ_f R_f Aᵀ ξ_f)/dt = Σ_f R_f (Ȧᵀ ξ_f + Aᵀ ξ̇_f).
  rotation_rate_ = Eigen::Map<const Eigen::Matrix3d>(v_ + 3);
  small_rate_.setZero();
  for (Eigen::Index f = 0; f < (size_ - 12) / 3; ++f)
    small_rate_.noalias() += marker_->rotation.middleCols<3>(3 * f) *
                             (rotation_rate_.transpose() * Eigen::Map<const Eigen::Vector3d>(q_ + 12 + 3 * f) +
                              rotation_.transpose() * Eigen::Map<const Eigen::Vector3d>(v_ + 12 + 3 * f));
}

Eigen::Vector3d detail::MarkerFrame::position_rate() const {
  if (kind_ != Kind::ground && v_ == nullptr) throw std::logic_error("MarkerFrame: a rate before set_rates");
  switch (kind_) {
    case Kind::ground: return Eigen::Vector3d::Zero();
    case Kind::floating: {  // τ̇ + Ȧ ū_c + A Ψ_c η̇
      const Eigen::Map<const Eigen::VectorXd> v(v_, size_);
      return v.head<3>() + rotation_rate_ * local_ + rotation_ * (marker_->modal_displacement * v.tail(size_ - 7));
    }
    case Kind::gcms: break;
  }
  Eigen::Vector3d r = Eigen::Vector3d::Zero();  // (yᵀ ⊗ I3) q̇_b
  for (Eigen::Index k = 0; k < marker_->y.size(); ++k) r += marker_->y(k) * Eigen::Map<const Eigen::Vector3d>(v_ + 3 * k);
  return r;
}

Eigen::Vector3d detail::MarkerFrame::direction_rate(const Eigen::Vector3d& d) const {
  if (kind_ == Kind::ground) return Eigen::Vector3d::Zero();
  if (v_ == nullptr) throw std::logic_error("MarkerFrame: a rate before set_rates");
  // d/dt A (d − [d]× s) = (dA/dt) v − A (d × ṡ), v = d − d × s, s = R ξ̄ or Θ_c η.
  const Eigen::Vector3d v = d - d.cross(small_);
  return rotation_rate_ * v - rotation_ * d.cross(small_rate_);
}

void detail::MarkerFrame::add_transpose_product(const Eigen::Vector3d& w_r, const Eigen::Vector3d* d, const Eigen::Vector3d* w,
                                                int count, Eigen::Ref<Eigen::VectorXd> out) const {
  if (kind_ == Kind::ground) return;
  // Each direction's J_dᵀ w_k: its A (or p) columns directly, and through s = R ξ̄ (Θ_c η) the sum
  // σ = Σ_k (−A [d_k]×)ᵀ w_k = Σ_k d_k × (Aᵀ w_k), which every field's columns share.
  Eigen::Vector3d sigma = Eigen::Vector3d::Zero();
  for (int k = 0; k < count; ++k) sigma += d[k].cross(rotation_.transpose() * w[k]);
  if (kind_ == Kind::floating) {  // J_r = [I, ∂(A ū_c)/∂p, A Ψ_c]; J_d = [0, ∂(A v)/∂p, −A [d]× Θ_c]
    out.head<3>() += w_r;
    // Σ wᵀ (∂A/∂p_k) x over the pairs (w_r, ū_c) and (w_k, v_k) is ⟨∂A/∂p_k, Σ w xᵀ⟩.
    Eigen::Matrix3d weights = w_r * local_.transpose();
    for (int k = 0; k < count; ++k) weights.noalias() += w[k] * (d[k] - d[k].cross(small_)).transpose();
    const std::array<Eigen::Matrix3d, 4> partials = euler_rotation_partials(euler_);
    for (int k = 0; k < 4; ++k) out(3 + k) += partials[static_cast<std::size_t>(k)].cwiseProduct(weights).sum();
    out.tail(size_ - 7).noalias() += marker_->modal_displacement.transpose() * (rotation_.transpose() * w_r);
    out.tail(size_ - 7).noalias() += marker_->modal_rotation.transpose() * sigma;
    return;
  }
  // J_r = yᵀ ⊗ I3.
  for (Eigen::Index k = 0; k < marker_->y.size(); ++k) out.segment<3>(3 * k) += marker_->y(k) * w_r;
  // J_d's A columns: ∂(A v)/∂A(i, j) = e_i v_j, column 3 + 3j + i, i.e. vec(w vᵀ); and through s.
  Eigen::Map<Eigen::Matrix3d> by_a(out.data() + 3);
  for (int k = 0; k < count; ++k) by_a.noalias() += w[k] * (d[k] - d[k].cross(small_)).transpose();
  // With c_f = R_fᵀ σ: ∂s/∂A(i, j) = Σ_f R_f(:, j) ξ_f(i) gives Σ_f ξ_f c_fᵀ, and ∂s/∂ξ_f = R_f Aᵀ gives A c_f.
  for (Eigen::Index f = 0; f < (size_ - 12) / 3; ++f) {
    const Eigen::Vector3d c = marker_->rotation.middleCols<3>(3 * f).transpose() * sigma;
    by_a.noalias() += Eigen::Map<const Eigen::Vector3d>(q_ + 12 + 3 * f) * c.transpose();
    out.segment<3>(12 + 3 * f).noalias() += rotation_ * c;
  }
}

Eigen::Vector3d detail::MarkerFrame::direction(const Eigen::Vector3d& d) const {
  if (kind_ == Kind::ground) return d;
  return rotation_ * (d - d.cross(small_));
}

void detail::MarkerFrame::jacobian(const Eigen::Vector3d& d, Eigen::MatrixXd& jac) const {
  if (kind_ == Kind::ground) {
    jac.resize(3, 0);
    return;
  }
  if (kind_ == Kind::gcms && size_ > 12 && turned_ == nullptr)
    throw std::logic_error("MarkerFrame::jacobian after an evaluate without storage (marker " + marker_->name + ")");
  const Eigen::Matrix3d dx = skew(d);
  const Eigen::Vector3d v = d - dx * small_;
  jac.setZero(3, size_);
  if (kind_ == Kind::floating) {
    jac.middleCols<4>(3) = euler_rotation_derivative(euler_, v);
    jac.rightCols(size_ - 7).noalias() = (-rotation_ * dx) * marker_->modal_rotation;
    return;
  }
  // ∂(A v)/∂A(i, j) = e_i v_j + A ∂v/∂A(i, j), column 3 + 3j + i, with ∂v/∂A = −[d]× ∂(R ξ̄)/∂A.
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) jac(i, 3 + 3 * j + i) = v(j);
  if (turned_ == nullptr) return;
  const Eigen::Matrix3d turn = -rotation_ * dx;
  jac.middleCols<9>(3).noalias() += turn * small_by_a_;
  jac.rightCols(size_ - 12).noalias() = turn * *turned_;
}

Eigen::Vector3d marker_direction(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d) {
  detail::MarkerFrame frame;
  Eigen::MatrixXd storage;
  frame.evaluate(m, q_b, storage);
  return frame.direction(d);
}

void marker_direction_jacobian(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d, Eigen::MatrixXd& jac) {
  detail::MarkerFrame frame;
  Eigen::MatrixXd storage;
  frame.evaluate(m, q_b, storage);
  frame.jacobian(d, jac);
}

Eigen::MatrixXd marker_direction_jacobian(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d) {
  Eigen::MatrixXd jac;
  marker_direction_jacobian(m, q_b, d, jac);
  return jac;
}

}  // namespace flexbody::runtime
