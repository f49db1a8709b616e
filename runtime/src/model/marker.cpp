#include "flexbody/runtime/marker.hpp"

#include "flexbody/runtime/ffrf_dynamics.hpp"
#include "flexbody/runtime/gcms_elastic.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

namespace flexbody::runtime {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

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

}  // namespace

Marker interface_marker(const BodyModel& model, int body, const std::string& body_name, const std::string& name) {
  for (const format::Interface& i : model.interfaces)
    if (i.name == name) return finished(model, make_marker(body, body_name + "/" + name, i.y_row, i.rotation));
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

namespace {

// R ξ̄ = Σ_f R_f Aᵀ ξ_f, the marker's small rotation, without forming ξ̄.
Eigen::Vector3d small_rotation(const Marker& m, const Eigen::Matrix3d& a, const VectorRef& xi) {
  Eigen::Vector3d theta = Eigen::Vector3d::Zero();
  for (Eigen::Index f = 0; f < xi.size() / 3; ++f) {
    const Eigen::Vector3d xi_bar = a.transpose() * xi.segment<3>(3 * f);
    theta.noalias() += m.rotation.middleCols<3>(3 * f) * xi_bar;
  }
  return theta;
}

}  // namespace

Eigen::Vector3d marker_direction(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d) {
  if (m.body == kGround) return d;
  check_coordinates(m, q_b);
  if (m.floating) {  // A(p) (d − [d]× Θ_c η)
    const Eigen::Vector3d theta = m.modal_rotation * q_b.tail(q_b.size() - 7);
    return euler_rotation(euler_of(q_b)) * (d - skew(d) * theta);
  }
  const Eigen::Matrix3d a = orientation_of(q_b);
  const auto xi = q_b.tail(q_b.size() - 12);
  if (xi.size() == 0) return a * d;
  return a * (d - skew(d) * small_rotation(m, a, xi));
}

void marker_direction_jacobian(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d, Eigen::MatrixXd& jac) {
  if (m.body == kGround) {
    jac.resize(3, 0);
    return;
  }
  check_coordinates(m, q_b);
  if (m.floating) {
    const Eigen::Index n = q_b.size() - 7;
    const Eigen::Vector4d p = euler_of(q_b);
    const Eigen::Matrix3d dx = skew(d);
    const Eigen::Vector3d theta = m.modal_rotation * q_b.tail(n);
    jac.setZero(3, q_b.size());
    jac.middleCols<4>(3) = euler_rotation_derivative(p, d - dx * theta);
    const Eigen::Matrix3d turn = -euler_rotation(p) * dx;
    jac.rightCols(n).noalias() = turn * m.modal_rotation;
    return;
  }
  const Eigen::Index n = q_b.size(), n_xi = n - 12;
  const Eigen::Matrix3d a = orientation_of(q_b);
  const auto xi = q_b.tail(n_xi);
  jac.setZero(3, n);
  Eigen::Vector3d v = d;
  Eigen::Matrix<double, 3, 9> dv_da = Eigen::Matrix<double, 3, 9>::Zero();
  if (n_xi > 0) {
    const Eigen::Matrix3d dx = skew(d);
    v -= dx * small_rotation(m, a, xi);
    // ∂(R ξ̄)/∂A(i, j) = Σ_f R_f(:, j) ξ_f(i) (ξ̄_f = Aᵀ ξ_f), column 3j + i; then ∂v/∂a = −[d]× of it.
    Eigen::Matrix<double, 3, 9> r_d = Eigen::Matrix<double, 3, 9>::Zero();
    for (Eigen::Index f = 0; f < n_xi / 3; ++f) {
      const Eigen::Vector3d xi_f = xi.segment<3>(3 * f);
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) r_d.col(3 * j + i) += xi_f(i) * m.rotation.col(3 * f + j);
    }
    dv_da.noalias() = -dx * r_d;
    // ∂u/∂ξ_f = −A [d]× R_f Aᵀ
    const Eigen::Matrix3d turn = -a * dx;
    for (Eigen::Index f = 0; f < n_xi / 3; ++f)
      jac.block<3, 3>(0, 12 + 3 * f).noalias() = turn * m.rotation.middleCols<3>(3 * f) * a.transpose();
  }
  // ∂(A v)/∂A(i, j) = e_i v_j + A ∂v/∂A(i, j), column 3 + 3j + i.
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) jac(i, 3 + 3 * j + i) += v(j);
  jac.middleCols<9>(3).noalias() += a * dv_da;
}

Eigen::MatrixXd marker_direction_jacobian(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d) {
  Eigen::MatrixXd jac;
  marker_direction_jacobian(m, q_b, d, jac);
  return jac;
}

}  // namespace flexbody::runtime
