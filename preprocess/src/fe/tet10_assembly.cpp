#include "flexbody/preprocess/tet10_assembly.hpp"

#include "flexbody/format/tet10_element.hpp"

#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace flexbody::preprocess {

Tet10Mesh quadratic_mesh(const TetMesh& linear) {
  Tet10Mesh mesh;
  mesh.tets.resize(linear.tets.rows(), 10);
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> middles;
  std::vector<Eigen::RowVector3d> added;
  const auto corners = static_cast<std::int32_t>(linear.nodes.rows());
  for (Eigen::Index e = 0; e < linear.tets.rows(); ++e) {
    for (int a = 0; a < 4; ++a) mesh.tets(e, a) = linear.tets(e, a);
    for (int k = 0; k < 6; ++k) {
      const auto [i, j] = format::kTet10Edges[static_cast<std::size_t>(k)];
      const std::int32_t p = linear.tets(e, i), q = linear.tets(e, j);
      const auto key = std::minmax(p, q);
      auto [where, inserted] = middles.try_emplace({key.first, key.second}, corners + static_cast<std::int32_t>(added.size()));
      if (inserted) added.push_back(0.5 * (linear.nodes.row(p) + linear.nodes.row(q)));
      mesh.tets(e, 4 + k) = where->second;
    }
  }
  mesh.nodes.resize(corners + static_cast<Eigen::Index>(added.size()), 3);
  mesh.nodes.topRows(corners) = linear.nodes;
  for (std::size_t k = 0; k < added.size(); ++k) mesh.nodes.row(corners + static_cast<Eigen::Index>(k)) = added[k];
  return mesh;
}

Tet10Matrices assemble_tet10(const Tet10Mesh& mesh, const Material& material, format::Tet10MassRule rule) {
  check_material(material);
  const double lambda = lame_lambda(material), mu = shear_modulus(material);
  std::vector<Eigen::Triplet<double, std::int64_t>> k_entries, m_entries;
  k_entries.reserve(static_cast<std::size_t>(mesh.tets.rows()) * 465);
  m_entries.reserve(static_cast<std::size_t>(mesh.tets.rows()) * 55);
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    format::Tet10Nodes x;
    for (int a = 0; a < 10; ++a) x.row(a) = mesh.nodes.row(mesh.tets(e, a));
    if (!(format::tet10_jacobian_determinants(x).minCoeff() > 0.0))
      throw std::invalid_argument("quadratic element " + std::to_string(e) + " is inverted or folded: its Jacobian "
                                  "determinant is not positive at every Gauss point and node");
    const Eigen::Matrix<double, 30, 30> k = format::tet10_stiffness(x, lambda, mu);
    const Eigen::Matrix<double, 10, 10> m = format::tet10_mass(x, material.density, rule);
    for (int b = 0; b < 10; ++b)
      for (int a = 0; a < 10; ++a) {
        const std::int64_t nb = mesh.tets(e, b), na = mesh.tets(e, a);
        if (nb <= na) m_entries.emplace_back(nb, na, m(b, a));
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            if (3 * nb + r <= 3 * na + c) k_entries.emplace_back(3 * nb + r, 3 * na + c, k(3 * b + r, 3 * a + c));
      }
  }
  Tet10Matrices out;
  out.stiffness.resize(mesh.dof_count(), mesh.dof_count());
  out.stiffness.setFromTriplets(k_entries.begin(), k_entries.end());
  out.scalar_mass.resize(mesh.node_count(), mesh.node_count());
  out.scalar_mass.setFromTriplets(m_entries.begin(), m_entries.end());
  return out;
}

}  // namespace flexbody::preprocess
