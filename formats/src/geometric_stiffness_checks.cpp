// geometric_stiffness_checks.cpp: the checks of /geometric_stiffness (SCHEMA.md, "Geometric stiffness"), part of
// check_structure, check_finite and check_ranges.
#include "body_checks.hpp"
#include "check_helpers.hpp"

#include <algorithm>
#include <array>
#include <set>
#include <string_view>

namespace flexbody::format::detail {
namespace {

bool one_of(std::string_view text, const std::array<const char*, 6>& allowed) {
  return std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return text == a; });
}

}  // namespace

void check_geometric_stiffness_structure(const BodyData& body, const std::string& context) {
  const GeometricStiffness& g = body.geometric_stiffness;
  if (g.empty() && g.matrices.empty()) return;
  std::set<std::string> interfaces, seen;
  for (const Interface& i : body.interfaces) interfaces.insert(i.name);
  for (std::size_t k = 0; k < g.cases.size(); ++k) {
    const std::string& name = g.cases[k];
    const std::string path = "/geometric_stiffness/cases" + index(static_cast<Eigen::Index>(k));
    const std::size_t colon = name.rfind(':');
    const std::string source = colon == std::string::npos ? name : name.substr(0, colon);
    const std::string load = colon == std::string::npos ? std::string() : name.substr(colon + 1);
    const bool centrifugal = source == "centrifugal" && one_of(load, kCentrifugalCases);
    const bool at_interface = interfaces.count(source) > 0 && one_of(load, kInterfaceLoadCases);
    if (!centrifugal && !at_interface)
      fail(context, path + " is \"" + name + "\", expected centrifugal:xx ... :yz or <interface>:fx ... :mz with an "
                    "interface of /interfaces");
    if (!seen.insert(name).second) fail(context, path + " repeats \"" + name + "\"");
  }
  if (g.matrices.size() != g.cases.size())
    fail(context, "/geometric_stiffness has " + std::to_string(g.matrices.size()) + " matrices but " +
                      std::to_string(g.cases.size()) + " cases (one matrix per case)");
  const Eigen::Index size = 4 + body.gcms.field_count();
  for (std::size_t k = 0; k < g.matrices.size(); ++k)
    if (g.matrices[k].rows() != size || g.matrices[k].cols() != size)
      fail(context, "/geometric_stiffness/matrices of case " + g.cases[k] + " is " +
                        std::to_string(g.matrices[k].rows()) + " x " + std::to_string(g.matrices[k].cols()) +
                        ", expected " + std::to_string(size) + " x " + std::to_string(size) + " (4 + n_f, as /gcms/G)");
}

void check_geometric_stiffness_finite(const BodyData& body, const std::string& context) {
  const GeometricStiffness& g = body.geometric_stiffness;
  for (std::size_t k = 0; k < g.matrices.size(); ++k)
    check_values(g.matrices[k], "/geometric_stiffness/matrices (case " + g.cases[k] + ")", context);
}

// Written symmetric (the mean of Ĝ and Ĝᵀ, exact), with row and column 0 exact zeros: the constant field has no
// gradient. (Its computed round-off had no scale to be judged against: the blocks carry different units.)
void check_geometric_stiffness_ranges(const BodyData& body, const std::string& context) {
  const GeometricStiffness& g = body.geometric_stiffness;
  for (std::size_t k = 0; k < g.matrices.size(); ++k) {
    const Eigen::MatrixXd& m = g.matrices[k];
    const std::string path = "/geometric_stiffness/matrices (case " + g.cases[k] + ")";
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      for (Eigen::Index c = 0; c < r; ++c)
        if (m(r, c) != m(c, r))
          fail(context, path + index(r) + index(c) + " is " + number(m(r, c)) + " but " + index(c) + index(r) +
                            " is " + number(m(c, r)) + "; the matrix is symmetric");
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      if (m(0, c) != 0.0)
        fail(context, path + "[0]" + index(c) + " is " + number(m(0, c)) + ", expected 0 (the constant field has no "
                          "gradient)");
  }
}

}  // namespace flexbody::format::detail
