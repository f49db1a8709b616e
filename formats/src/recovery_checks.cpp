// recovery_checks.cpp: the checks of /recovery (SCHEMA.md, "Recovery"), part of check_structure and
// check_finite.
#include "body_checks.hpp"
#include "check_helpers.hpp"

#include <set>

namespace flexbody::format::detail {

void check_recovery_structure(const BodyData& body, const std::string& context) {
  const Eigen::Index n_n = body.mesh.nodes.rows(), n_f = body.gcms.field_count();
  std::set<std::string> names;
  for (const RecoveryRegion& r : body.recovery) {
    const std::string path = "/recovery/" + r.name;
    if (r.name.empty() || r.name.find_first_of("/,") != std::string::npos || r.name == "order" ||
        r.name == "stress_components")
      fail(context, "output region name \"" + r.name + "\" is not allowed (non-empty, no '/' or ',', not \"order\" "
                    "or \"stress_components\")");
    if (!names.insert(r.name).second) fail(context, "two output regions are named \"" + r.name + "\"");
    const Eigen::Index k = r.nodes.size();
    if (k < 1) fail(context, path + "/nodes is empty, expected at least one node");
    for (Eigen::Index j = 0; j < k; ++j) {
      if (r.nodes(j) < 0 || r.nodes(j) >= n_n)
        fail(context, path + "/nodes" + index(j) + " is " + std::to_string(r.nodes(j)) + " but the mesh has " +
                          std::to_string(n_n) + " nodes");
      if (j > 0 && r.nodes(j) <= r.nodes(j - 1))
        fail(context, path + "/nodes" + index(j) + " is not above the previous entry (ascending, unique)");
    }
    if (r.stress_modes.rows() != 6 * k || r.stress_modes.cols() != 3 * n_f)
      fail(context, path + "/stress_modes has shape " + std::to_string(r.stress_modes.rows()) + " x " +
                        std::to_string(r.stress_modes.cols()) + ", expected " + std::to_string(6 * k) + " x " +
                        std::to_string(3 * n_f) + " (6 k x 3 n_f)");
  }
}

void check_recovery_finite(const BodyData& body, const std::string& context) {
  for (const RecoveryRegion& r : body.recovery) check_values(r.stress_modes, "/recovery/" + r.name + "/stress_modes", context);
}

}  // namespace flexbody::format::detail
