#pragma once
// report_text.hpp (internal): how fbprep's report and body summary write numbers.

#include <Eigen/Core>
#include <fmt/format.h>

#include <string>

namespace flexbody::preprocess::detail {

/// "[x, y, z]" with 6 significant digits each.
inline std::string vector3(const Eigen::Vector3d& v) {
  return fmt::format("[{:.6g}, {:.6g}, {:.6g}]", v(0), v(1), v(2));
}

}  // namespace flexbody::preprocess::detail
