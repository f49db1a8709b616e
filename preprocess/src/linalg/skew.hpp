#pragma once
// skew.hpp (internal): the cross-product matrix, for the rigid-body fields of interfaces and Craig-Bampton modes.

#include <Eigen/Core>

namespace flexbody::preprocess::detail {

/// [v]ₓ with [v]ₓ w = v × w.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

}  // namespace flexbody::preprocess::detail
