#pragma once
// What rigid_pendulum_test.cpp and rigid_body_test.cpp share: the bar's dimensions, its rigid model, the elliptic
// integral and a pendulum system.
#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

namespace rigid_pendulum {

namespace fr = flexbody::runtime;

inline constexpr double kLength = 1.0, kWidth = 0.05, kMass = 19.625, kGravity = 9.81;

// A rigid 1 x 0.05 x 0.05 m bar: G = [[m, 0], [0, J]] with J = ∫ x xᵀ dm = m diag(L², w², w²) / 12.
inline fr::BodyModel rigid_bar() {
  return fr::rigid_body_model(kMass, kMass / 12.0 * Eigen::Vector3d(kLength * kLength, kWidth * kWidth, kWidth * kWidth).asDiagonal(),
                              "rigid bar");
}

// K(k), the complete elliptic integral of the first kind, by the arithmetic-geometric mean: K = π / (2 AGM(1, k')).
inline double elliptic_k(double k) {
  double a = 1.0, b = std::sqrt(1.0 - k * k);
  for (int i = 0; i < 40; ++i) {
    const double next = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = next;
  }
  return std::numbers::pi / (2.0 * a);
}

// The bar along x with its left end at the origin, pinned there about z; gravity along −y.
// The pivot at `pivot` (the origin by default).
inline fr::System pendulum(const fr::BodyModel& model, const Eigen::Vector3d& pivot = Eigen::Vector3d::Zero()) {
  fr::System system;
  fr::BodyState state;
  state.position = pivot + Eigen::Vector3d(kLength / 2, 0, 0);
  const int bar = system.add_body("bar", model, state);
  const fr::Marker pin = fr::point_marker(model, bar, "bar", Eigen::Vector3d(-kLength / 2, 0, 0));
  system.add_joint(fr::make_joint("pivot", fr::JointType::revolute, pin, fr::ground_marker(pivot),
                                  Eigen::Vector3d::UnitZ(), system.initial_coordinates(), Eigen::VectorXd()));
  system.set_gravity(Eigen::Vector3d(0, -kGravity, 0));
  return system;
}

inline double angle_of(const Eigen::VectorXd& q) { return std::atan2(q(4), q(3)); }  // A(1,0), A(0,0)

}  // namespace rigid_pendulum
