#include "flexbody/runtime/joint.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

namespace flexbody::runtime {
namespace {

// A body-fixed direction at a marker and its Jacobian (0 columns on ground).
struct Direction {
  Eigen::Vector3d value;
  Eigen::MatrixXd jacobian;
};
Direction direction(const Marker& m, const VectorRef& q, const Eigen::Vector3d& d) {
  if (m.body == kGround) return {d, Eigen::MatrixXd(3, 0)};
  return {marker_direction(m, q, d), marker_direction_jacobian(m, q, d)};
}

// The frame of a marker's body: A for a body, identity for ground (directions are fixed in it at assembly).
Eigen::Matrix3d frame_of(const Marker& m, const VectorRef& q) { return marker_body_orientation(m, q); }

Eigen::MatrixXd position_jacobian(const Marker& m, const VectorRef& q) {
  return m.body == kGround ? Eigen::MatrixXd(3, 0) : marker_position_jacobian(m, q);
}

// Appends rows to an evaluation.
struct Rows {
  JointEvaluation& out;
  int next = 0;
  void add(double value, const Eigen::RowVectorXd& j1, const Eigen::RowVectorXd& j2) {
    out.residual(next) = value;
    if (j1.size()) out.jacobian_first.row(next) = j1;
    if (j2.size()) out.jacobian_second.row(next) = j2;
    ++next;
  }
  // u · w with u at marker 1, w at marker 2.
  void dot(const Direction& u, const Direction& w) {
    add(u.value.dot(w.value), w.value.transpose() * u.jacobian, u.value.transpose() * w.jacobian);
  }
};

// The three rows that keep two triads aligned: z1·y2, z1·x2, y1·x2.
void orientation_rows(Rows& rows, const Joint& j, const VectorRef& q1, const VectorRef& q2) {
  const Direction x2 = direction(j.second, q2, j.triad_second.col(0));
  const Direction y2 = direction(j.second, q2, j.triad_second.col(1));
  const Direction y1 = direction(j.first, q1, j.triad_first.col(1));
  const Direction z1 = direction(j.first, q1, j.triad_first.col(2));
  rows.dot(z1, y2);
  rows.dot(z1, x2);
  rows.dot(y1, x2);
}

}  // namespace

int Joint::rows() const {
  switch (type) {
    case JointType::spherical: return 3;
    case JointType::fixed: return 6;
    case JointType::revolute: return 5;
    case JointType::prismatic: return 5;
    case JointType::driven_revolute: return 6;
  }
  return 0;
}

Joint make_joint(const std::string& name, JointType type, Marker first, Marker second, const Eigen::Vector3d& axis,
                 const VectorRef& q1, const VectorRef& q2, std::function<double(double)> angle) {
  Joint j;
  j.name = name;
  j.type = type;
  j.first = std::move(first);
  j.second = std::move(second);
  j.angle = std::move(angle);
  const Eigen::Matrix3d a1 = frame_of(j.first, q1), a2 = frame_of(j.second, q2);
  j.triad_first = a1.transpose();
  j.triad_second = a2.transpose();
  const bool has_axis = type == JointType::revolute || type == JointType::prismatic || type == JointType::driven_revolute;
  if (has_axis) {
    if (!(axis.norm() > 0.0) || !axis.allFinite())
      throw std::invalid_argument("joint '" + name + "': the axis must be a non-zero vector");
    const Eigen::Vector3d e = axis.normalized();
    Eigen::Vector3d n = e.unitOrthogonal(), m = e.cross(n);
    j.axis_first = a1.transpose() * e;
    j.axis_second = a2.transpose() * e;
    j.normal_a = a2.transpose() * n;
    j.normal_b = a2.transpose() * m;
    j.reference_first = a1.transpose() * n;
  }
  if (type == JointType::driven_revolute && !j.angle)
    throw std::invalid_argument("joint '" + name + "': a driven revolute joint needs an angle function");
  const Eigen::Vector3d gap = marker_position(j.first, q1) - marker_position(j.second, q2);
  if (type == JointType::prismatic) {
    j.offset = {gap.dot(a2 * j.normal_a), gap.dot(a2 * j.normal_b)};
  } else {
    const double size = std::max({1.0, marker_position(j.first, q1).norm(), marker_position(j.second, q2).norm()});
    if (gap.norm() > 1e-9 * size)
      throw std::invalid_argument("joint '" + name + "': its markers " + j.first.name + " and " + j.second.name +
                                  " are " + std::to_string(gap.norm()) + " m apart; the scene must start assembled");
  }
  return j;
}

JointEvaluation evaluate_joint(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2) {
  const int n_rows = j.rows();
  JointEvaluation out;
  out.residual.resize(n_rows);
  out.jacobian_first = Eigen::MatrixXd::Zero(n_rows, j.first.body == kGround ? 0 : q1.size());
  out.jacobian_second = Eigen::MatrixXd::Zero(n_rows, j.second.body == kGround ? 0 : q2.size());
  Rows rows{out};
  const Eigen::Vector3d gap = marker_position(j.first, q1) - marker_position(j.second, q2);
  const Eigen::MatrixXd jr1 = position_jacobian(j.first, q1), jr2 = position_jacobian(j.second, q2);
  if (j.type != JointType::prismatic)
    for (int k = 0; k < 3; ++k) rows.add(gap(k), jr1.row(k), -jr2.row(k));
  switch (j.type) {
    case JointType::spherical: break;
    case JointType::fixed: orientation_rows(rows, j, q1, q2); break;
    case JointType::prismatic: {
      for (int k = 0; k < 2; ++k) {
        const Direction n = direction(j.second, q2, k == 0 ? j.normal_a : j.normal_b);
        const Eigen::RowVectorXd j2 = n.jacobian.cols() ? Eigen::RowVectorXd(-n.value.transpose() * jr2 + gap.transpose() * n.jacobian)
                                                        : Eigen::RowVectorXd();
        rows.add(gap.dot(n.value) - j.offset(k), n.value.transpose() * jr1, j2);
      }
      orientation_rows(rows, j, q1, q2);
      break;
    }
    case JointType::revolute:
    case JointType::driven_revolute: {
      const Direction axis = direction(j.first, q1, j.axis_first);
      rows.dot(axis, direction(j.second, q2, j.normal_a));
      rows.dot(axis, direction(j.second, q2, j.normal_b));
      if (j.type == JointType::driven_revolute) {
        // u1 · (cos φ n_b − sin φ n_a) = 0 holds when marker 1 has turned by φ about the axis.
        const double phi = j.angle(t);
        rows.dot(direction(j.first, q1, j.reference_first),
                 direction(j.second, q2, std::cos(phi) * j.normal_b - std::sin(phi) * j.normal_a));
      }
      break;
    }
  }
  return out;
}

}  // namespace flexbody::runtime
