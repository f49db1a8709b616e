// Joint Jacobians against central differences, for every joint type, body-body and body-ground, with interface
// markers that have a small rotation (R ≠ 0) on a deformed, slightly non-orthogonal state: the exact Jacobians the
// issue asks for, including the ξ and R terms of the marker directions.
#include "flexbody/runtime/joint.hpp"

#include "model/joint_rows.hpp"  // internal: the Newton iteration's matrix-free products

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

namespace fr = flexbody::runtime;

namespace {

constexpr Eigen::Index kFields = 4;

fr::Marker random_marker(int body) {
  fr::Marker m;
  m.body = body;
  m.name = "body " + std::to_string(body);
  m.y = Eigen::VectorXd::Random(4 + kFields) * 0.3;
  m.y(0) = 1.0;
  m.rotation = Eigen::MatrixXd::Random(3, 3 * kFields) * 5.0;
  return m;
}

Eigen::VectorXd random_state(double angle) {
  Eigen::VectorXd q(12 + 3 * kFields);
  const Eigen::Matrix3d a = Eigen::AngleAxisd(angle, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix() +
                            1e-3 * Eigen::Matrix3d::Random();
  q << Eigen::Vector3d::Random(), Eigen::Map<const Eigen::Matrix<double, 9, 1>>(a.data()),
      2e-3 * Eigen::VectorXd::Random(3 * kFields);
  return q;
}

// A marker on a floating-frame body (coordinates [τ; p; η], n_m modes), as marker.cpp's `finished` makes one.
constexpr Eigen::Index kModes = 5;
fr::Marker random_floating_marker(int body) {
  fr::Marker m = random_marker(body);
  m.floating = true;
  m.modal_displacement = Eigen::Matrix3Xd::Random(3, kModes) * 0.1;
  m.modal_rotation = Eigen::Matrix3Xd::Random(3, kModes) * 0.5;
  return m;
}
Eigen::VectorXd random_floating_state() {
  Eigen::VectorXd q(7 + kModes);
  q << Eigen::Vector3d::Random(), Eigen::Vector4d::Random().normalized(), 0.05 * Eigen::VectorXd::Random(kModes);
  return q;
}

// max |analytic − numeric| / max |numeric| over the columns of one body's Jacobian.
double jacobian_error(const fr::Joint& joint, double t, const Eigen::VectorXd& q1, const Eigen::VectorXd& q2, bool first) {
  const fr::JointEvaluation e = fr::evaluate_joint(joint, t, q1, q2);
  const Eigen::MatrixXd& analytic = first ? e.jacobian_first : e.jacobian_second;
  const Eigen::VectorXd& q = first ? q1 : q2;
  Eigen::MatrixXd numeric(analytic.rows(), q.size());
  for (Eigen::Index c = 0; c < q.size(); ++c) {
    const double h = 1e-6;
    Eigen::VectorXd plus = q, minus = q;
    plus(c) += h;
    minus(c) -= h;
    const Eigen::VectorXd rp = first ? fr::evaluate_joint(joint, t, plus, q2).residual : fr::evaluate_joint(joint, t, q1, plus).residual;
    const Eigen::VectorXd rm = first ? fr::evaluate_joint(joint, t, minus, q2).residual : fr::evaluate_joint(joint, t, q1, minus).residual;
    numeric.col(c) = (rp - rm) / (2 * h);
  }
  return (analytic - numeric).cwiseAbs().maxCoeff() / numeric.cwiseAbs().maxCoeff();
}

}  // namespace

TEST(JointDerivatives, EveryJointTypeMatchesCentralDifferences) {
  std::srand(11);
  const Eigen::VectorXd q1 = random_state(0.4), q2 = random_state(-1.1);
  for (const fr::JointType type : {fr::JointType::spherical, fr::JointType::fixed, fr::JointType::revolute,
                                   fr::JointType::prismatic, fr::JointType::driven_revolute}) {
    for (const bool to_ground : {false, true}) {
      SCOPED_TRACE(static_cast<int>(type) * 2 + (to_ground ? 1 : 0));
      fr::Joint joint;
      joint.name = "j";
      joint.type = type;
      joint.first = random_marker(0);
      joint.second = to_ground ? fr::ground_marker(Eigen::Vector3d(0.1, 0.2, 0.3)) : random_marker(1);
      joint.axis_first = Eigen::Vector3d(0.2, 0.3, 1.0).normalized();
      joint.axis_second = Eigen::Vector3d(-0.1, 0.2, 1.0).normalized();
      joint.normal_a = joint.axis_second.unitOrthogonal();
      joint.normal_b = joint.axis_second.cross(joint.normal_a);
      joint.reference_first = joint.axis_first.unitOrthogonal();
      joint.triad_first = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
      joint.triad_second = Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY()).toRotationMatrix();
      joint.offset = Eigen::Vector2d(0.01, -0.02);
      joint.angle = [](double t) { return 0.7 * t * t; };
      const Eigen::VectorXd ground;
      // Central differences with h = 1e-6 on residuals of size ~1: truncation ~1e-12, rounding ~1e-10 relative.
      EXPECT_LT(jacobian_error(joint, 0.8, q1, to_ground ? ground : q2, true), 1e-7);
      if (!to_ground) {
        EXPECT_LT(jacobian_error(joint, 0.8, q1, q2, false), 1e-7);
      }
    }
  }
}

// ∂Φ/∂t of a driven revolute joint's angle row (driven_row_time_derivative) against the residual's central difference
// in t: with the angle's rate given it is exact; without, φ is differenced over ∛(ε (1 + |t|/h)) h with h the time
// scale passed, at the start of a run and 10⁴ steps into it. At a 1 mm part's spin, 3.3e5 rad/s over steps of 6e-8 s,
// the old fixed step of ∛ε s (6e-6 s) spanned 2 rad.
TEST(JointDerivatives, TheDrivenAngleRowsTimeDerivativeFollowsTheScenesTimeScale) {
  std::srand(12);
  const Eigen::VectorXd q1 = random_state(0.4), q2 = random_state(-1.1);
  fr::Joint joint;
  joint.name = "drive";
  joint.type = fr::JointType::driven_revolute;
  joint.first = random_marker(0);
  joint.second = random_marker(1);
  joint.axis_first = Eigen::Vector3d(0.2, 0.3, 1.0).normalized();
  joint.axis_second = Eigen::Vector3d(-0.1, 0.2, 1.0).normalized();
  joint.normal_a = joint.axis_second.unitOrthogonal();
  joint.normal_b = joint.axis_second.cross(joint.normal_a);
  joint.reference_first = joint.axis_first.unitOrthogonal();
  std::array<Eigen::MatrixXd, 2> frames;
  for (const double speed : {1.0, 3.3e5}) {  // [rad/s]
    const double step = 0.02 / speed;      // an integrator step of 0.02 rad
    for (const double steps : {0.0, 15.0, 1e4}) {
      SCOPED_TRACE(std::to_string(speed) + " rad/s, t = " + std::to_string(steps) + " steps");
      const double t = steps * step;
      const std::function<double(double)> angle = [speed](double s) { return speed * s + 0.1 * std::sin(speed * s); };
      joint.angle = angle;
      joint.angle_rate = [speed](double s) { return speed * (1.0 + 0.1 * std::cos(speed * s)); };
      // The reference: dΦ/dφ by a central difference in φ alone (truncation δ²/6 ~ 2e-11), times the exact φ̇.
      const double delta = 1e-5, rate = joint.angle_rate(t);
      fr::Joint shifted = joint;
      shifted.angle = [&angle, t, delta](double) { return angle(t) + delta; };
      const double up = fr::evaluate_joint(shifted, t, q1, q2).residual(5);
      shifted.angle = [&angle, t, delta](double) { return angle(t) - delta; };
      const double down = fr::evaluate_joint(shifted, t, q1, q2).residual(5);
      const double reference = rate * (up - down) / (2 * delta);
      ASSERT_GT(std::abs(reference), 0.05 * speed);
      EXPECT_NEAR(fr::driven_row_time_derivative(joint, t, step, q1, q2, frames), reference, 1e-9 * speed);
      joint.angle_rate = nullptr;  // φ differenced over ∛(ε (1 + |t|/h)) h
      EXPECT_NEAR(fr::driven_row_time_derivative(joint, t, step, q1, q2, frames), reference, 1e-7 * speed);
    }
  }
  joint.type = fr::JointType::revolute;
  EXPECT_EQ(fr::driven_row_time_derivative(joint, 0.1, 1e-3, q1, q2, frames), 0.0);
}

// The Newton iteration's residual, rates Φ_q q̇ and products Φ_qᵀ μ are formed without the Jacobian
// (model/joint_rows.hpp); against evaluate_joint's Jacobian, which the test above checks against differences: every
// joint type, GCMS and floating-frame markers and ground on either side, with and without removed rows. The two
// sum the same terms in a different order: agreement to 1e-13 of the terms' size.
TEST(JointDerivatives, TheMatrixFreeProductsMatchTheJacobian) {
  std::srand(13);
  struct Side {
    fr::Marker marker;
    Eigen::VectorXd q, v;
  };
  auto gcms = [](int body, double angle) { return Side{random_marker(body), random_state(angle), Eigen::VectorXd::Random(12 + 3 * kFields)}; };
  auto floating = [](int body) { return Side{random_floating_marker(body), random_floating_state(), Eigen::VectorXd::Random(7 + kModes)}; };
  auto ground = [] { return Side{fr::ground_marker(Eigen::Vector3d(0.1, 0.2, 0.3)), Eigen::VectorXd(), Eigen::VectorXd()}; };
  // A rigid body in either form: the GCMS's τ and A without fields, and position and Euler parameters without modes
  // (fbsim's `modes: rigid`).
  auto rigid_gcms = [](int body) {
    fr::Marker m = random_marker(body);
    m.y.conservativeResize(4);
    m.rotation.resize(3, 0);
    return Side{m, random_state(0.9).head(12), Eigen::VectorXd::Random(12)};
  };
  auto rigid_floating = [&floating](int body) {
    Side s = floating(body);
    s.marker.modal_displacement.resize(3, 0);
    s.marker.modal_rotation.resize(3, 0);
    s.q.conservativeResize(7);
    s.v.conservativeResize(7);
    return s;
  };
  const std::vector<std::pair<Side, Side>> pairs = {
      {gcms(0, 0.4), gcms(1, -1.1)}, {gcms(0, 0.4), ground()}, {ground(), gcms(1, 2.0)},
      {floating(0), gcms(1, 0.3)},   {gcms(0, 0.7), floating(1)}, {ground(), floating(1)},
      {rigid_gcms(0), rigid_floating(1)}, {rigid_floating(0), ground()}};
  int case_index = 0;
  for (const fr::JointType type : {fr::JointType::spherical, fr::JointType::fixed, fr::JointType::revolute,
                                   fr::JointType::prismatic, fr::JointType::driven_revolute}) {
    for (const auto& [one, two] : pairs) {
      for (const unsigned removed : {0U, 0b10010U}) {
        SCOPED_TRACE("case " + std::to_string(case_index++));
        fr::Joint joint;
        joint.name = "j";
        joint.type = type;
        joint.first = one.marker;
        joint.second = two.marker;
        joint.axis_first = Eigen::Vector3d(0.2, 0.3, 1.0).normalized();
        joint.normal_a = Eigen::Vector3d(-0.1, 0.2, 1.0).normalized().unitOrthogonal();
        joint.normal_b = Eigen::Vector3d(-0.1, 0.2, 1.0).normalized().cross(joint.normal_a);
        joint.reference_first = joint.axis_first.unitOrthogonal();
        joint.triad_first = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
        joint.triad_second = Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY()).toRotationMatrix();
        joint.offset = Eigen::Vector2d(0.01, -0.02);
        joint.angle = [](double t) { return 0.7 * t * t; };
        joint.removed = type == fr::JointType::spherical ? (removed & 0b111U) : removed;
        const double t = 0.8;
        const fr::JointEvaluation e = fr::evaluate_joint(joint, t, one.q, two.q);
        const int rows = joint.rows();
        ASSERT_EQ(e.residual.size(), rows);
        Eigen::VectorXd residual(rows), rate(rows), only(rows);
        fr::detail::joint_residual_and_rate(joint, t, one.q, two.q, one.v, two.v, residual, rate);
        fr::detail::joint_residual(joint, t, one.q, two.q, only);
        EXPECT_LT((residual - e.residual).cwiseAbs().maxCoeff(), 1e-15 * (1.0 + e.residual.cwiseAbs().maxCoeff()));
        EXPECT_EQ((only - residual).cwiseAbs().maxCoeff(), 0.0);
        Eigen::VectorXd expected_rate = Eigen::VectorXd::Zero(rows);
        double rate_size = 0.0;  // Σ |J_ij v_j|: the size of the terms summed
        if (e.jacobian_first.cols() > 0) {
          expected_rate += e.jacobian_first * one.v;
          rate_size = std::max(rate_size, (e.jacobian_first.cwiseAbs() * one.v.cwiseAbs()).maxCoeff());
        }
        if (e.jacobian_second.cols() > 0) {
          expected_rate += e.jacobian_second * two.v;
          rate_size = std::max(rate_size, (e.jacobian_second.cwiseAbs() * two.v.cwiseAbs()).maxCoeff());
        }
        EXPECT_LT((rate - expected_rate).cwiseAbs().maxCoeff(), 1e-13 * rate_size);
        const Eigen::VectorXd mu = Eigen::VectorXd::Random(rows);
        Eigen::VectorXd first, second;
        fr::detail::joint_transpose_product(joint, t, one.q, two.q, mu, first, second);
        ASSERT_EQ(first.size(), e.jacobian_first.cols());
        ASSERT_EQ(second.size(), e.jacobian_second.cols());
        if (first.size() > 0) {
          const double size = (e.jacobian_first.cwiseAbs().transpose() * mu.cwiseAbs()).maxCoeff();
          EXPECT_LT((first - e.jacobian_first.transpose() * mu).cwiseAbs().maxCoeff(), 1e-13 * size);
        }
        if (second.size() > 0) {
          const double size = (e.jacobian_second.cwiseAbs().transpose() * mu.cwiseAbs()).maxCoeff();
          EXPECT_LT((second - e.jacobian_second.transpose() * mu).cwiseAbs().maxCoeff(), 1e-13 * size);
        }
      }
    }
  }
}
