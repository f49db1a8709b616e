#pragma once
// Small rotation helpers of the runtime's sources (not installed).

#include <Eigen/Core>

namespace flexbody::runtime::detail {

/// [v]×, the cross-product matrix: [v]× w = v × w.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

/// E(p) = [−e, [e]× + e0 I] (3 x 4) of Euler parameters p = (e0, e): ω = 2 E(p) ṗ is the global angular velocity, and
/// ṗ = ½ E(p)ᵀ ω for unit p.
inline Eigen::Matrix<double, 3, 4> euler_global_velocity_matrix(const Eigen::Vector4d& p) {
  Eigen::Matrix<double, 3, 4> e;
  e.col(0) = -p.tail<3>();
  e.rightCols<3>() = skew(p.tail<3>()) + p(0) * Eigen::Matrix3d::Identity();
  return e;
}

}  // namespace flexbody::runtime::detail
