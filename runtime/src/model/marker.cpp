#include "flexbody/runtime/marker.hpp"

#include "flexbody/runtime/gcms_elastic.hpp"

#include <Eigen/Geometry>

#include <stdexcept>

namespace flexbody::runtime {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

void check_coordinates(const Marker& m, const VectorRef& q_b) {
  if (q_b.size() != 3 * m.y.size())
    throw std::invalid_argument("marker " + m.name + ": " + std::to_string(q_b.size()) + " body coordinates, expected " +
                                std::to_string(3 * m.y.size()));
}

}  // namespace

Marker interface_marker(const BodyModel& model, int body, const std::string& body_name, const std::string& name) {
  for (const format::Interface& i : model.interfaces)
    if (i.name == name) return {body, body_name + "/" + name, i.y_row, i.rotation, Eigen::Vector3d::Zero()};
  std::string known;
  for (const format::Interface& i : model.interfaces) known += (known.empty() ? "" : ", ") + i.name;
  throw std::invalid_argument(model.source + ": no interface '" + name + "' (interfaces: " +
                              (known.empty() ? std::string("none") : known) + ")");
}

Marker point_marker(const BodyModel& model, int body, const std::string& body_name, const Eigen::Vector3d& point) {
  Marker m{body, body_name + "/point", Eigen::VectorXd::Zero(4 + model.field_count()),
           Eigen::MatrixXd::Zero(3, 3 * model.field_count()), Eigen::Vector3d::Zero()};
  m.y(0) = 1.0;
  m.y.segment<3>(1) = point;
  return m;
}

Marker node_marker(const BodyModel& model, int body, const std::string& body_name, Eigen::Index node) {
  if (node < 0 || node >= model.nodes.rows())
    throw std::invalid_argument(model.source + ": node " + std::to_string(node) + " does not exist (the mesh has " +
                                std::to_string(model.nodes.rows()) + " nodes)");
  Marker m = point_marker(model, body, body_name, model.nodes.row(node).transpose());
  m.name = body_name + "/node " + std::to_string(node);
  m.y.tail(model.field_count()) = field_row(model, node).transpose();
  return m;
}

Marker ground_marker(const Eigen::Vector3d& point) {
  return {kGround, "ground", Eigen::VectorXd(), Eigen::MatrixXd(), point};
}

Eigen::Vector3d marker_position(const Marker& m, const VectorRef& q_b) {
  if (m.body == kGround) return m.ground_point;
  check_coordinates(m, q_b);
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < m.y.size(); ++k) r += m.y(k) * q_b.segment<3>(3 * k);
  return r;
}

Eigen::MatrixXd marker_position_jacobian(const Marker& m) {
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(3, 3 * m.y.size());
  for (Eigen::Index k = 0; k < m.y.size(); ++k) jac.block<3, 3>(0, 3 * k).diagonal().setConstant(m.y(k));
  return jac;
}

Eigen::Vector3d marker_direction(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d) {
  if (m.body == kGround) return d;
  check_coordinates(m, q_b);
  const Eigen::Matrix3d a = orientation_of(q_b);
  const auto xi = q_b.tail(q_b.size() - 12);
  if (xi.size() == 0) return a * d;
  return a * (d - skew(d) * (m.rotation * body_frame_coordinates(a, xi)));
}

Eigen::MatrixXd marker_direction_jacobian(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d) {
  if (m.body == kGround) return Eigen::MatrixXd(3, 0);
  check_coordinates(m, q_b);
  const Eigen::Index n = q_b.size(), n_xi = n - 12;
  const Eigen::Matrix3d a = orientation_of(q_b);
  const auto xi = q_b.tail(n_xi);
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(3, n);
  Eigen::Vector3d v = d;
  Eigen::Matrix<double, 3, 9> dv_da = Eigen::Matrix<double, 3, 9>::Zero();
  if (n_xi > 0) {
    const Eigen::Matrix3d dx = skew(d);
    v -= dx * (m.rotation * body_frame_coordinates(a, xi));
    dv_da = -dx * m.rotation * body_frame_coordinates_derivative(xi);
    // ∂u/∂ξ_f = −A [d]× R_f Aᵀ
    for (Eigen::Index f = 0; f < n_xi / 3; ++f)
      jac.block<3, 3>(0, 12 + 3 * f) = -a * dx * m.rotation.middleCols<3>(3 * f) * a.transpose();
  }
  // ∂(A v)/∂A(i, j) = e_i v_j + A ∂v/∂A(i, j), column 3 + 3j + i.
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) jac(i, 3 + 3 * j + i) += v(j);
  jac.middleCols<9>(3) += a * dv_da;
  return jac;
}

}  // namespace flexbody::runtime
