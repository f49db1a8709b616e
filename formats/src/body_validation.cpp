// body_validation.cpp: validate() and the checks it shares with the reader.
#include "body_checks.hpp"
#include "check_helpers.hpp"

#include "flexbody/format/body_file.hpp"

#include <cmath>
#include <set>
#include <string_view>

namespace flexbody::format {
namespace detail {
namespace {

void check_options(const Provenance& provenance, const std::string& context) {
  std::set<std::string_view> seen;
  for (std::size_t i = 0; i < provenance.options.size(); ++i) {
    const std::string& name = provenance.options[i].first;
    const std::string where = "/provenance/options: option " + std::to_string(i);
    if (name.empty()) fail(context, where + " has an empty name");
    if (name.find(',') != std::string::npos) {
      fail(context, where + " is named \"" + name + "\"; option names must not contain ','");
    }
    if (name == "order") fail(context, where + " is named \"order\", which the schema reserves");
    if (!seen.insert(name).second) fail(context, where + " repeats the name \"" + name + "\"");
  }
}

}  // namespace

void check_structure(const BodyData& body, const std::string& context) {
  const BodyMesh& mesh = body.mesh;
  const Eigen::Index n_n = mesh.nodes.rows();
  if (n_n < 4) fail(context, "/mesh/nodes has " + std::to_string(n_n) + " rows, expected at least 4 nodes");
  if (mesh.tets.rows() < 1) fail(context, "/mesh/tets has no rows, expected at least 1 tetrahedron");
  if (mesh.element_order != 1 && mesh.element_order != 2) {
    fail(context, "/mesh/element_order is " + std::to_string(mesh.element_order) +
                      ", expected 1 (linear 4-node tetrahedra) or 2 (quadratic 10-node tetrahedra)");
  }
  if (mesh.tets.cols() != BodyMesh::nodes_per_element(mesh.element_order)) {
    fail(context, "/mesh/tets has " + std::to_string(mesh.tets.cols()) + " columns, expected " +
                      std::to_string(BodyMesh::nodes_per_element(mesh.element_order)) + " for element_order " +
                      std::to_string(mesh.element_order));
  }
  check_indices(mesh.tets, n_n, "/mesh/tets", context);
  check_indices(mesh.surface_triangles, n_n, "/mesh/surface_triangles", context);

  const Modes& modes = body.modes;
  const Eigen::Index n_m = modes.count();
  if (modes.relative_residuals.size() != n_m) {
    fail(context, "/reduction/relative_residuals has " + std::to_string(modes.relative_residuals.size()) +
                      " entries, expected " + std::to_string(n_m) + " (n_m, the length of /reduction/frequencies_hz)");
  }
  if (modes.upsilon.rows() != n_n || modes.upsilon.cols() != 3 * n_m) {
    fail(context, "/reduction/upsilon has shape " + std::to_string(modes.upsilon.rows()) + " x " +
                      std::to_string(modes.upsilon.cols()) + ", expected " + std::to_string(n_n) + " x " +
                      std::to_string(3 * n_m) + " (n_n x 3 n_m)");
  }
  check_options(body.provenance, context);
  check_gcms_structure(body, context);
  check_interfaces_structure(body, context);
  check_recovery_structure(body, context);
  check_geometric_stiffness_structure(body, context);
  if (modes.static_correction_modes < 0 || modes.static_correction_modes > n_m)
    fail(context, "/reduction/static_correction_modes is " + std::to_string(modes.static_correction_modes) +
                      ", expected 0 to n_m = " + std::to_string(n_m));
  if (modes.kind == "craig-bampton" && modes.static_correction_modes != 0)
    fail(context, "/reduction/static_correction_modes is " + std::to_string(modes.static_correction_modes) +
                      ", expected 0 for craig-bampton modes (the static responses are part of its basis)");
  if (modes.static_correction_modes > static_cast<Eigen::Index>(modes.static_loads.size()))
    fail(context, "/reduction/static_correction_modes is " + std::to_string(modes.static_correction_modes) +
                      " but /reduction/static_loads names " + std::to_string(modes.static_loads.size()) +
                      " loads (at most one mode each)");
  for (std::size_t k = 0; k < modes.static_loads.size(); ++k)
    if (modes.static_loads[k].empty() || modes.static_loads[k].find(',') != std::string::npos)
      fail(context, "/reduction/static_loads" + index(static_cast<Eigen::Index>(k)) + " is \"" + modes.static_loads[k] +
                        "\"; labels are non-empty and have no ','");
}

void check_finite(const BodyData& body, const std::string& context) {
  check_value(body.material.youngs_modulus, "/material/youngs_modulus", context);
  check_value(body.material.poisson_ratio, "/material/poisson_ratio", context);
  check_value(body.material.density, "/material/density", context);
  check_value(body.mass.mass, "/mass/total", context);
  check_values(body.mass.center_of_mass_input, "/mass/center_of_mass_input", context);
  check_values(body.mass.inertia_about_com, "/mass/inertia_about_com", context);
  check_values(body.mesh.nodes, "/mesh/nodes", context);
  check_value(body.modes.shift, "/reduction/shift", context);
  check_values(body.modes.frequencies_hz, "/reduction/frequencies_hz", context);
  check_values(body.modes.relative_residuals, "/reduction/relative_residuals", context);
  check_values(body.modes.fixed_interface_frequencies_hz, "/reduction/fixed_interface_frequencies_hz", context);
  check_values(body.modes.upsilon, "/reduction/upsilon", context);
  check_gcms_finite(body, context);
  check_interfaces_finite(body, context);
  check_recovery_finite(body, context);
  check_geometric_stiffness_finite(body, context);
}

void check_ranges(const BodyData& body, const std::string& context) {
  check_positive(body.mass.mass, "/mass/total", "kg", context);
  check_positive(body.material.youngs_modulus, "/material/youngs_modulus", "Pa", context);
  check_positive(body.material.density, "/material/density", "kg/m^3", context);
  const double nu = body.material.poisson_ratio;
  if (!(nu > -1.0 && nu < 0.5)) {
    fail(context, "/material/poisson_ratio is " + number(nu) + ", expected -1 < nu < 0.5");
  }
  const Eigen::VectorXd& f = body.modes.frequencies_hz;
  for (Eigen::Index m = 0; m < f.size(); ++m) {
    const std::string path = "/reduction/frequencies_hz" + index(m);
    if (!(f[m] > 0.0)) {
      fail(context, path + " is " + number(f[m]) + " Hz, expected > 0 (rigid-body modes are not stored)");
    }
    if (m > 0 && f[m] < f[m - 1]) {
      fail(context, path + " = " + number(f[m]) + " Hz is below /reduction/frequencies_hz" + index(m - 1) + " = " +
                        number(f[m - 1]) + " Hz; frequencies must be ascending");
    }
  }
  if (body.modes.kind != "free-free" && body.modes.kind != "craig-bampton")
    fail(context, "/reduction/kind is \"" + body.modes.kind + "\", expected \"free-free\" or \"craig-bampton\"");
  const Eigen::VectorXd& fixed = body.modes.fixed_interface_frequencies_hz;
  if (body.modes.kind == "free-free" && fixed.size() > 0)
    fail(context, "/reduction/fixed_interface_frequencies_hz has entries, but free-free modes have no fixed interfaces");
  for (Eigen::Index m = 0; m < fixed.size(); ++m)
    if (!(fixed[m] > 0.0) || (m > 0 && fixed[m] < fixed[m - 1]))
      fail(context, "/reduction/fixed_interface_frequencies_hz" + index(m) + " is " + number(fixed[m]) +
                        " Hz, expected positive and ascending");
  const Eigen::VectorXd& r = body.modes.relative_residuals;
  for (Eigen::Index m = 0; m < r.size(); ++m) {
    if (r[m] < 0.0) fail(context, "/reduction/relative_residuals" + index(m) + " is " + number(r[m]) + ", expected >= 0");
  }
  check_gcms_ranges(body, context);
  check_recovery_ranges(body, context);
  check_interfaces_ranges(body, context);
  check_geometric_stiffness_ranges(body, context);
}

}  // namespace detail

void validate(const BodyData& body) {
  const std::string context = "body data";
  detail::check_structure(body, context);
  detail::check_finite(body, context);
  detail::check_ranges(body, context);
}

}  // namespace flexbody::format
