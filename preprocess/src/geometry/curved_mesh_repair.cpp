#include "flexbody/preprocess/curved_mesh_repair.hpp"

#include "flexbody/format/tet10_element.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace flexbody::preprocess {
namespace {

format::Tet10Nodes element_nodes(const Tet10Mesh& mesh, Eigen::Index e) {
  format::Tet10Nodes x;
  for (int a = 0; a < 10; ++a) x.row(a) = mesh.nodes.row(mesh.tets(e, a));
  return x;
}

}  // namespace

std::vector<Eigen::Index> folded_elements(const Tet10Mesh& mesh) {
  std::vector<Eigen::Index> folded;
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e)
    if (!(format::tet10_jacobian_determinants(element_nodes(mesh, e)).minCoeff() > 0.0)) folded.push_back(e);
  return folded;
}

Straightening straighten_folded_elements(Tet10Mesh& mesh) {
  Straightening done;
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e) {  // the fallback's premise: straight elements are valid
    const format::Tet10Nodes x = element_nodes(mesh, e);
    const double six_volume = (x.row(1) - x.row(0)).cross(x.row(2) - x.row(0)).dot(x.row(3) - x.row(0));
    if (!(six_volume > 0.0))
      throw std::runtime_error(fmt::format("quadratic element {} cannot be straightened: its corners' tetrahedron "
                                           "has no positive volume", e));
  }
  // Each round moves at least one curved edge of every folded element onto its chord (a folded element always has
  // one: a straight one is not folded), so the rounds end within the number of edges; in practice in one or two.
  for (std::vector<Eigen::Index> folded = folded_elements(mesh); !folded.empty(); folded = folded_elements(mesh)) {
    ++done.rounds;
    done.elements += static_cast<int>(folded.size());
    for (const Eigen::Index e : folded)
      for (int k = 0; k < 6; ++k) {
        const auto [i, j] = format::kTet10Edges[static_cast<std::size_t>(k)];
        const Eigen::RowVector3d chord = 0.5 * (mesh.nodes.row(mesh.tets(e, i)) + mesh.nodes.row(mesh.tets(e, j)));
        auto node = mesh.nodes.row(mesh.tets(e, 4 + k));
        const double move = (node - chord).norm();
        if (move == 0.0) continue;
        node = chord;
        ++done.nodes;
        done.largest_move_m = std::max(done.largest_move_m, move);
      }
  }
  return done;
}

}  // namespace flexbody::preprocess
