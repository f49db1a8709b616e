// recovery_checks.cpp: the checks of /recovery (SCHEMA.md, "Recovery"), part of check_structure,
// check_finite and check_ranges.
#include "body_checks.hpp"
#include "check_helpers.hpp"

#include "flexbody/format/tet10_element.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <limits>
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

// A stress mode is the nodal average of element stresses under the displacement field Ῡ'(:, f) e_d, so it cannot
// exceed what the stiffest element can make of that field. Every entry of ∇u at a node of an element is at most
// U_f Σ_b |g_b| with U_f = max_i |Ῡ'(i, f)| and g_b the entry's weight of node b: for a linear tetrahedron with heights
// h_i (|∇N_i| = 1/h_i) at most 4 U_f / h_min; for a quadratic one the extrapolated gradients of
// format/tet10_element.hpp, summed. Every stress component is at most (3 |λ| + 2 μ) times that (|λ|: λ < 0 for
// ν < 0). An entry above this bound (by more than rounding) was not computed from this mesh, material and fields: a
// damaged file (byte flips that stay finite made non-finite von Mises stresses in ParaView).
namespace {

double largest_linear_gradient(const BodyData& body, const std::string& context) {
  double smallest_height = std::numeric_limits<double>::infinity();
  const RowMatrixX3d& x = body.mesh.nodes;
  for (Eigen::Index t = 0; t < body.mesh.tets.rows(); ++t) {
    Eigen::Vector3d p[4];
    for (int k = 0; k < 4; ++k) p[k] = x.row(body.mesh.tets(t, k)).transpose();
    const double six_volume = std::abs((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]));
    if (!(six_volume > 0.0))  // a flat element has no stress modes to bound them with
      fail(context, "/mesh/tets" + index(t) + " has zero volume, so no stress of /recovery can be checked against it");
    for (int k = 0; k < 4; ++k) {  // the height over the face opposite node k: 3 V / area = 6 V / (2 area)
      const Eigen::Vector3d& a = p[(k + 1) % 4], &b = p[(k + 2) % 4], &c = p[(k + 3) % 4];
      const double twice_area = (b - a).cross(c - a).norm();
      if (twice_area > 0.0) smallest_height = std::min(smallest_height, six_volume / twice_area);
    }
  }
  return 4.0 / smallest_height;
}

double largest_quadratic_gradient(const BodyData& body, const std::string& context) {
  double largest = 0.0;
  for (Eigen::Index t = 0; t < body.mesh.tets.rows(); ++t) {
    Tet10Nodes x;
    for (int a = 0; a < 10; ++a) x.row(a) = body.mesh.nodes.row(body.mesh.tets(t, a));
    const Tet10RecoveryGradients g = tet10_recovery_gradients(x);
    if (!(g.volume > 0.0))
      fail(context, "/mesh/tets" + index(t) + " is inverted or folded (its Jacobian is not positive at a Gauss point), "
                    "so no stress of /recovery can be checked against it");
    for (const auto& at_node : g.at_node) largest = std::max(largest, at_node.cwiseAbs().colwise().sum().maxCoeff());
  }
  return largest;
}

}  // namespace

void check_recovery_ranges(const BodyData& body, const std::string& context) {
  if (body.recovery.empty()) return;
  const double e = body.material.youngs_modulus, nu = body.material.poisson_ratio;
  const double lambda = std::abs(e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))), mu = e / (2.0 * (1.0 + nu));
  const double largest_gradient = body.mesh.element_order == 2 ? largest_quadratic_gradient(body, context)
                                                               : largest_linear_gradient(body, context);
  const Eigen::Index n_f = body.gcms.field_count();
  for (const RecoveryRegion& r : body.recovery)
    for (Eigen::Index c = 0; c < r.stress_modes.cols() && c < 3 * n_f; ++c) {
      const double largest_field = body.gcms.fields.col(c / 3).cwiseAbs().maxCoeff();
      const double bound = (3.0 * lambda + 2.0 * mu) * largest_gradient * largest_field * (1.0 + 1e-9);
      for (Eigen::Index row = 0; row < r.stress_modes.rows(); ++row)
        if (!(std::abs(r.stress_modes(row, c)) <= bound))
          fail(context, "/recovery/" + r.name + "/stress_modes" + index(row) + index(c) + " is " +
                            number(r.stress_modes(row, c)) + " Pa kg^-1/2 m^-1, above " + number(bound) +
                            ", the most that the mesh's stiffest element can make of field " + std::to_string(c / 3) +
                            " (damaged or not computed from this mesh and material)");
    }
}

}  // namespace flexbody::format::detail
