// interface_checks.cpp: the checks of /interfaces (SCHEMA.md, "Interfaces"), part of check_structure,
// check_finite and check_ranges.
#include "body_checks.hpp"
#include "check_helpers.hpp"

#include <set>

namespace flexbody::format::detail {

void check_interfaces_structure(const BodyData& body, const std::string& context) {
  const Eigen::Index n_n = body.mesh.nodes.rows(), n_f = body.gcms.field_count();
  std::set<std::string> names;
  for (const Interface& i : body.interfaces) {
    const std::string path = "/interfaces/" + i.name;
    if (i.name.empty() || i.name.find_first_of("/,") != std::string::npos || i.name == "order")
      fail(context, "interface name \"" + i.name + "\" is not allowed (non-empty, no '/' or ',', not \"order\")");
    if (!names.insert(i.name).second) fail(context, "two interfaces are named \"" + i.name + "\"");
    if (i.coupling != "rbe2" && i.coupling != "rbe3")
      fail(context, path + "/coupling is \"" + i.coupling + "\", expected \"rbe2\" or \"rbe3\"");
    const Eigen::Index k = i.nodes.size();
    if (k < 1) fail(context, path + "/nodes is empty, expected at least one node");
    for (Eigen::Index j = 0; j < k; ++j) {
      if (i.nodes(j) < 0 || i.nodes(j) >= n_n)
        fail(context, path + "/nodes" + index(j) + " is " + std::to_string(i.nodes(j)) + " but the mesh has " +
                          std::to_string(n_n) + " nodes");
      if (j > 0 && i.nodes(j) <= i.nodes(j - 1))
        fail(context, path + "/nodes" + index(j) + " is not above the previous entry (ascending, unique)");
    }
    if (i.weights.size() != k)
      fail(context, path + "/weights has " + std::to_string(i.weights.size()) + " entries, expected " +
                        std::to_string(k) + " (one per node)");
    if (i.y_row.size() != 4 + n_f)
      fail(context, path + "/y_row has " + std::to_string(i.y_row.size()) + " entries, expected 4 + n_f = " +
                        std::to_string(4 + n_f));
    if (i.rotation.rows() != 3 || i.rotation.cols() != 3 * n_f)
      fail(context, path + "/rotation has shape " + std::to_string(i.rotation.rows()) + " x " +
                        std::to_string(i.rotation.cols()) + ", expected 3 x " + std::to_string(3 * n_f) + " (3 x 3 n_f)");
  }
}

void check_interfaces_finite(const BodyData& body, const std::string& context) {
  for (const Interface& i : body.interfaces) {
    const std::string path = "/interfaces/" + i.name;
    check_values(i.reference_point, path + "/reference_point", context);
    check_values(i.weights, path + "/weights", context);
    check_values(i.y_row, path + "/y_row", context);
    check_values(i.rotation, path + "/rotation", context);
  }
}

void check_interfaces_ranges(const BodyData& body, const std::string& context) {
  for (const Interface& i : body.interfaces) {
    const std::string path = "/interfaces/" + i.name;
    for (Eigen::Index j = 0; j < i.weights.size(); ++j)
      if (!(i.weights(j) > 0.0))
        fail(context, path + "/weights" + index(j) + " is " + number(i.weights(j)) + ", expected > 0");
    // Sums of k positive numbers: 1e-12 is round-off for any realistic k.
    if (std::abs(i.weights.sum() - 1.0) > 1e-12)
      fail(context, path + "/weights sum to " + number(i.weights.sum()) + ", expected 1");
    // The marker's reference point is the weighted node average, and y_row starts with [1, X̄_c].
    Eigen::Vector3d average = Eigen::Vector3d::Zero();
    for (Eigen::Index j = 0; j < i.nodes.size(); ++j) average += i.weights(j) * body.mesh.nodes.row(i.nodes(j)).transpose();
    const double size = std::max(body.mesh.nodes.cwiseAbs().maxCoeff(), 1e-300);
    if ((average - i.reference_point).norm() > 1e-12 * size)
      fail(context, path + "/reference_point is not the weighted average of its nodes");
    if (std::abs(i.y_row(0) - 1.0) > 1e-12 || (i.y_row.segment<3>(1) - i.reference_point).norm() > 1e-12 * size)
      fail(context, path + "/y_row does not start with [1, reference_point]");
  }
}

}  // namespace flexbody::format::detail
