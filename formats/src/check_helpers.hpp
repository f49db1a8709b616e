#pragma once
// check_helpers.hpp (private): the wording shared by every check of a body (paths as in SCHEMA.md,
// numbers that read back exactly), for body_validation.cpp and gcms_checks.cpp.

#include "flexbody/format/body_file.hpp"

#include <Eigen/Core>

#include <charconv>
#include <cmath>
#include <string>

namespace flexbody::format::detail {

[[noreturn]] inline void fail(const std::string& context, const std::string& problem) {
  throw BodyFileError(context + ": " + problem);
}

/// Shortest text that reads back as the same double ("10.5", "1e-09", "nan", "inf").
inline std::string number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

inline std::string index(Eigen::Index i) {
  std::string text(1, '[');  // built by appending: GCC 12 warns falsely on "literal" + std::string&&
  text += std::to_string(i);
  text += ']';
  return text;
}

template <class Derived>
void check_indices(const Eigen::MatrixBase<Derived>& elements, Eigen::Index node_count, const std::string& path,
                   const std::string& context) {
  for (Eigen::Index e = 0; e < elements.rows(); ++e) {
    for (Eigen::Index k = 0; k < elements.cols(); ++k) {
      const auto node = elements(e, k);
      if (node < 0 || node >= node_count) {
        fail(context, path + index(e) + " refers to node " + std::to_string(node) + " but the mesh has " +
                          std::to_string(node_count) + " nodes (valid: 0 to " + std::to_string(node_count - 1) +
                          ")");
      }
    }
  }
}

inline void check_value(double value, const std::string& path, const std::string& context) {
  if (!std::isfinite(value)) fail(context, path + " is " + number(value) + ", expected a finite number");
}

template <class Derived>
void check_values(const Eigen::DenseBase<Derived>& values, const std::string& path, const std::string& context) {
  for (Eigen::Index r = 0; r < values.rows(); ++r) {
    for (Eigen::Index c = 0; c < values.cols(); ++c) {
      if (!std::isfinite(values(r, c))) {
        const std::string at = values.cols() == 1 ? index(r) : index(r) + index(c);
        fail(context, path + at + " is " + number(values(r, c)) + ", expected a finite number");
      }
    }
  }
}

inline void check_positive(double value, const std::string& path, const char* unit, const std::string& context) {
  if (!(value > 0.0)) fail(context, path + " is " + number(value) + " " + unit + ", expected > 0");
}


}  // namespace flexbody::format::detail
