#include "flexbody/preprocess/tet10_assembly.hpp"

#include "flexbody/format/tet10_element.hpp"
#include "flexbody/preprocess/assembly.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
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

namespace {

// Element colours: no two elements of one colour share a node, elements keep their order within a colour. Greedy, 64
// colours per sweep over the elements that are still without one (a sweep's colours are bits of a node mask).
std::vector<std::vector<std::int32_t>> element_colours(const Tet10Mesh& mesh) {
  std::vector<std::vector<std::int32_t>> colours;
  std::vector<std::int32_t> remaining(static_cast<std::size_t>(mesh.element_count()));
  for (std::size_t e = 0; e < remaining.size(); ++e) remaining[e] = static_cast<std::int32_t>(e);
  std::vector<std::uint64_t> used(static_cast<std::size_t>(mesh.node_count()));
  while (!remaining.empty()) {
    std::fill(used.begin(), used.end(), 0);
    const std::size_t first = colours.size();
    colours.resize(first + 64);
    std::vector<std::int32_t> later;
    for (const std::int32_t e : remaining) {
      std::uint64_t taken = 0;
      for (int a = 0; a < 10; ++a) taken |= used[static_cast<std::size_t>(mesh.tets(e, a))];
      if (taken == ~std::uint64_t{0}) {
        later.push_back(e);
        continue;
      }
      const int colour = std::countr_one(taken);
      colours[first + static_cast<std::size_t>(colour)].push_back(e);
      for (int a = 0; a < 10; ++a) used[static_cast<std::size_t>(mesh.tets(e, a))] |= std::uint64_t{1} << colour;
    }
    while (colours.size() > first && colours.back().empty()) colours.pop_back();
    remaining = std::move(later);
  }
  return colours;
}

}  // namespace

Tet10Matrices assemble_tet10(const Tet10Mesh& mesh, const Material& material, format::Tet10MassRule rule) {
  check_material(material);
  const double lambda = lame_lambda(material), mu = shear_modulus(material);
  const NodeGraph graph = NodeGraph::build(mesh);  // checks the node indices
  Tet10Matrices out{vector_pattern(graph), scalar_pattern(graph)};
  const std::int64_t* k_start = out.stiffness.outerIndexPtr();
  double* k_values = out.stiffness.valuePtr();
  double* m_values = out.scalar_mass.valuePtr();
  std::int64_t bad = std::numeric_limits<std::int64_t>::max();
  // Colour by colour, the elements of a colour in parallel: each entry gets at most one element's share per colour, in
  // colour order, so the sums do not depend on the thread count.
  for (const std::vector<std::int32_t>& colour : element_colours(mesh)) {
    const auto count = static_cast<std::int64_t>(colour.size());
#pragma omp parallel for schedule(dynamic, 16) reduction(min : bad)
    for (std::int64_t n = 0; n < count; ++n) {
      const std::int32_t e = colour[static_cast<std::size_t>(n)];
      format::Tet10Nodes x;
      for (int a = 0; a < 10; ++a) x.row(a) = mesh.nodes.row(mesh.tets(e, a));
      if (!(format::tet10_jacobian_determinants(x).minCoeff() > 0.0)) {
        bad = std::min<std::int64_t>(bad, e);
        continue;
      }
      const Eigen::Matrix<double, 30, 30> k = format::tet10_stiffness(x, lambda, mu);
      const Eigen::Matrix<double, 10, 10> m = format::tet10_mass(x, material.density, rule);
      for (int a = 0; a < 10; ++a) {  // column node j = tets(e, a), row node i = tets(e, b) <= j
        const std::int32_t j = mesh.tets(e, a);
        for (int b = 0; b < 10; ++b) {
          const std::int32_t i = mesh.tets(e, b);
          if (i > j) continue;
          const std::int64_t position = position_in_column(graph, j, i);
          m_values[graph.column_start[static_cast<std::size_t>(j)] + position] += m(b, a);
          for (int c = 0; c < 3; ++c)
            for (int r = 0; r <= (i == j ? c : 2); ++r)
              k_values[k_start[3 * j + c] + 3 * position + r] += k(3 * b + r, 3 * a + c);
        }
      }
    }
    if (bad != std::numeric_limits<std::int64_t>::max()) break;
  }
  if (bad != std::numeric_limits<std::int64_t>::max())
    throw std::invalid_argument("quadratic element " + std::to_string(bad) + " is inverted or folded: its Jacobian "
                                "determinant is not positive at every Gauss point and node");
  return out;
}

}  // namespace flexbody::preprocess
