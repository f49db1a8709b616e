#pragma once
// A vector's finiteness in one pass (the integrator's test of its corrections and states; not installed).

#include <Eigen/Core>

#include <cmath>

namespace flexbody::runtime::detail {

/// Whether every entry is finite, in one vectorized pass: a NaN or an infinity in any entry makes the sum NaN or
/// infinite. (Eigen's allFinite() tests entry by entry; a sum of finite entries could only overflow near 1e308, which
/// is no state to go on from either.)
inline bool all_finite(const Eigen::VectorXd& x) { return std::isfinite(x.sum()); }

}  // namespace flexbody::runtime::detail
