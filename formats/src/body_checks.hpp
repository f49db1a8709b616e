#pragma once
// body_checks.hpp (private): the checks behind validate(), shared with the reader so that both report
// a problem in the same words. Each throws BodyFileError("<context>: <problem>"), where the problem
// names the item by its path in the file (SCHEMA.md), e.g. "/mesh/tets[12] refers to node 57 ...".

#include "flexbody/format/body_data.hpp"

#include <string>

namespace flexbody::format::detail {

/// Sizes against each other: node and element counts, node indices in range, element order,
/// mode counts of the mode datasets, option names.
void check_structure(const BodyData& body, const std::string& context);

/// Every floating-point value finite; names the first bad value with its index.
void check_finite(const BodyData& body, const std::string& context);

/// Physical ranges: positive mass, modulus and density, Poisson ratio in (-1, 0.5), positive
/// ascending frequencies, non-negative residuals.
void check_ranges(const BodyData& body, const std::string& context);

/// The /gcms part of each check above (gcms_checks.cpp).
void check_gcms_structure(const BodyData& body, const std::string& context);
void check_gcms_finite(const BodyData& body, const std::string& context);
void check_gcms_ranges(const BodyData& body, const std::string& context);

/// The /interfaces part of each check above (interface_checks.cpp).
void check_interfaces_structure(const BodyData& body, const std::string& context);
void check_interfaces_finite(const BodyData& body, const std::string& context);
void check_interfaces_ranges(const BodyData& body, const std::string& context);

/// The /recovery part of each check above (recovery_checks.cpp).
void check_recovery_structure(const BodyData& body, const std::string& context);
void check_recovery_finite(const BodyData& body, const std::string& context);
void check_recovery_ranges(const BodyData& body, const std::string& context);

/// The /geometric_stiffness part of each check above (geometric_stiffness_checks.cpp).
void check_geometric_stiffness_structure(const BodyData& body, const std::string& context);
void check_geometric_stiffness_finite(const BodyData& body, const std::string& context);
void check_geometric_stiffness_ranges(const BodyData& body, const std::string& context);

}  // namespace flexbody::format::detail
