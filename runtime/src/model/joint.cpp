#include "flexbody/runtime/joint.hpp"

#include "joint_rows.hpp"
#include "marker_frame.hpp"

#include <Eigen/Geometry>

#include <array>
#include <bit>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace flexbody::runtime {
namespace {

// The frame of a marker's body: A for a body, identity for ground (directions are fixed in it at assembly).
Eigen::Matrix3d frame_of(const Marker& m, const VectorRef& q) { return marker_body_orientation(m, q); }

// row = wᵀ J (1 x 3 times 3 x n) into a row of a column-major matrix, column by column: no temporary.
void set_row(Eigen::MatrixXd& out, int row, const Eigen::Vector3d& w, const Eigen::MatrixXd& jac) {
  for (Eigen::Index c = 0; c < jac.cols(); ++c) out(row, c) = w.dot(jac.col(c));
}

}  // namespace

int Joint::rows() const { return type_rows() - std::popcount(removed); }

int Joint::type_rows() const {
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
                 const VectorRef& q1, const VectorRef& q2, std::function<double(double)> angle,
                 std::function<double(double)> angle_rate) {
  Joint j;
  j.name = name;
  j.type = type;
  j.first = std::move(first);
  j.second = std::move(second);
  j.angle = std::move(angle);
  j.angle_rate = std::move(angle_rate);
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
  }
  // Markers apart are the assembly's to close (initial_assembly.hpp); GeneralizedAlpha refuses a state that violates a
  // row.
  return j;
}

double driven_row_time_derivative(const Joint& j, double t, double time_scale, const VectorRef& q1, const VectorRef& q2,
                                  std::array<Eigen::MatrixXd, 2>& frames) {
  if (j.type != JointType::driven_revolute) return 0.0;
  double rate = 0.0;
  if (j.angle_rate) {
    rate = j.angle_rate(t);
  } else {
    // ∛(ε (1 + |t|/h)) h: the step that balances truncation (step² φ‴) against the angle's rounding (ε |φ|, |φ| growing
    // with t), with time in units of h; a step ∛ε (|t| + h) let the truncation grow as t².
    const double h = std::abs(time_scale);
    const double dt = std::cbrt(std::numeric_limits<double>::epsilon() * (1.0 + std::abs(t) / h)) * h;
    const double before = t - dt, after = t + dt;  // divided by after − before: exact, whatever t + dt rounds to
    rate = (j.angle(after) - j.angle(before)) / (after - before);
  }
  // The row is u1 · (cos φ n_b − sin φ n_a) (evaluate_joint); its φ-derivative u1 · (−sin φ n_b − cos φ n_a), with
  // the directions linear in the body-fixed vector they turn.
  const double phi = j.angle(t);
  detail::MarkerFrame f1, f2;
  f1.evaluate(j.first, q1, frames[0]);
  f2.evaluate(j.second, q2, frames[1]);
  return rate * f1.direction(j.reference_first).dot(f2.direction(-std::sin(phi) * j.normal_b - std::cos(phi) * j.normal_a));
}

void evaluate_joint(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2, JointEvaluation& out) {
  // With removed rows, all rows go into the all_ storage (swapped in, so that no evaluation after the first
  // allocates), and the kept ones are copied out below.
  const bool some_removed = j.removed != 0;
  if (some_removed) {
    out.residual.swap(out.all_residual);
    out.jacobian_first.swap(out.all_first);
    out.jacobian_second.swap(out.all_second);
  }
  // The rows as joint_rows.hpp describes them (the matrix-free products use the same description).
  const detail::JointForm form = detail::joint_form(j, t);
  const int n_rows = form.row_count;
  out.residual.resize(n_rows);
  out.jacobian_first.setZero(n_rows, j.first.body == kGround ? 0 : q1.size());
  out.jacobian_second.setZero(n_rows, j.second.body == kGround ? 0 : q2.size());
  const Eigen::Vector3d gap = marker_position(j.first, q1) - marker_position(j.second, q2);
  Eigen::MatrixXd &jr1 = out.position_first, &jr2 = out.position_second;
  if (j.first.body == kGround) jr1.resize(3, 0); else marker_position_jacobian(j.first, q1, jr1);
  if (j.second.body == kGround) jr2.resize(3, 0); else marker_position_jacobian(j.second, q2, jr2);
  // Each marker's rotation once, shared by its directions; the directions' values and Jacobians: marker 1's in
  // out.directions[0, 2), marker 2's in [2, 6).
  std::array<Eigen::Vector3d, 2> u;
  std::array<Eigen::Vector3d, 4> w;
  std::array<Eigen::MatrixXd, 6>& d = out.directions;
  if (form.first_count + form.second_count > 0) {
    detail::MarkerFrame f1, f2;
    f1.evaluate(j.first, q1, out.frames[0]);
    f2.evaluate(j.second, q2, out.frames[1]);
    for (std::size_t k = 0; k < static_cast<std::size_t>(form.first_count); ++k) {
      u[k] = f1.direction(form.first[k]);
      f1.jacobian(form.first[k], d[k]);
    }
    for (std::size_t k = 0; k < static_cast<std::size_t>(form.second_count); ++k) {
      w[k] = f2.direction(form.second[k]);
      f2.jacobian(form.second[k], d[2 + k]);
    }
  }
  for (int r = 0; r < n_rows; ++r) {
    const detail::JointForm::Row& row = form.rows[static_cast<std::size_t>(r)];
    const auto a = static_cast<std::size_t>(row.a), b = static_cast<std::size_t>(row.b);
    switch (row.kind) {
      case detail::JointForm::Kind::gap:
        out.residual(r) = gap(row.a);
        if (jr1.cols()) out.jacobian_first.row(r) = jr1.row(row.a);
        if (jr2.cols()) out.jacobian_second.row(r) = -jr2.row(row.a);
        break;
      case detail::JointForm::Kind::along:  // gap · n with n at marker 2: ∂/∂q1 = nᵀ J_r1, ∂/∂q2 = −nᵀ J_r2 + gapᵀ J_n
        out.residual(r) = gap.dot(w[a]) - j.offset(row.b);
        set_row(out.jacobian_first, r, w[a], jr1);
        for (Eigen::Index c = 0; c < d[2 + a].cols(); ++c)
          out.jacobian_second(r, c) = -w[a].dot(jr2.col(c)) + gap.dot(d[2 + a].col(c));
        break;
      case detail::JointForm::Kind::dot:  // u · w with u at marker 1, w at marker 2
        out.residual(r) = u[a].dot(w[b]);
        set_row(out.jacobian_first, r, w[b], d[a]);
        set_row(out.jacobian_second, r, u[a], d[2 + b]);
        break;
    }
  }
  if (!some_removed) return;
  out.residual.swap(out.all_residual);
  out.jacobian_first.swap(out.all_first);
  out.jacobian_second.swap(out.all_second);
  const int kept = j.rows();
  out.residual.resize(kept);
  out.jacobian_first.resize(kept, out.all_first.cols());
  out.jacobian_second.resize(kept, out.all_second.cols());
  for (int k = 0, r = 0; k < n_rows; ++k) {
    if ((j.removed >> k) & 1U) continue;
    out.residual(r) = out.all_residual(k);
    out.jacobian_first.row(r) = out.all_first.row(k);
    out.jacobian_second.row(r) = out.all_second.row(k);
    ++r;
  }
}

std::string joint_row_meaning(const Joint& j, int row, const VectorRef& q1, const VectorRef& q2) {
  auto global = [](const Eigen::Vector3d& u) {  // a unit vector as [x, y, z], 2 decimals, no "-0"
    std::ostringstream out;
    out << std::fixed << std::setprecision(2) << '[';
    for (int k = 0; k < 3; ++k) out << (k ? ", " : "") << (std::abs(u(k)) < 0.005 ? 0.0 : u(k));
    out << ']';
    return out.str();
  };
  // A row u1 · w2 (u at marker 1, w at marker 2) stops the rotation of body 1 against body 2 about u × w.
  auto rotation = [&](const Eigen::Vector3d& u_first, const Eigen::Vector3d& w_second) {
    const Eigen::Vector3d about = marker_direction(j.first, q1, u_first).cross(marker_direction(j.second, q2, w_second));
    return "rotation about " + global(about.normalized());
  };
  const bool prismatic = j.type == JointType::prismatic;
  if (row < j.length_rows()) {
    if (prismatic) return "translation along " + global(marker_direction(j.second, q2, row == 0 ? j.normal_a : j.normal_b));
    return std::string("translation along ") + "xyz"[row];
  }
  const int orientation = row - j.length_rows();
  switch (j.type) {
    case JointType::fixed:
    case JointType::prismatic: {
      const Eigen::Vector3d u[3] = {j.triad_first.col(2), j.triad_first.col(2), j.triad_first.col(1)};
      const Eigen::Vector3d w[3] = {j.triad_second.col(1), j.triad_second.col(0), j.triad_second.col(0)};
      return rotation(u[orientation], w[orientation]);
    }
    case JointType::revolute:
    case JointType::driven_revolute:
      if (orientation == 2) return "rotation about the axis (the driven angle)";
      return rotation(j.axis_first, orientation == 0 ? j.normal_a : j.normal_b);
    case JointType::spherical: break;
  }
  return "row " + std::to_string(row + 1);
}

Eigen::VectorXd joint_type_residuals(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2) {
  Joint whole = j;
  whole.removed = 0;
  return evaluate_joint(whole, t, q1, q2).residual;
}

JointEvaluation evaluate_joint(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2) {
  JointEvaluation out;
  evaluate_joint(j, t, q1, q2, out);
  return out;
}

}  // namespace flexbody::runtime
