#include "shell_sewing.hpp"

#include "gmsh_session.hpp"

#include <gmsh.h>

#include <functional>
#include <map>
#include <numeric>
#include <vector>

namespace flexbody::preprocess::detail {
namespace {

int count(int dim) {
  gmsh::vectorpair entities;
  gmsh::model::getEntities(entities, dim);
  return static_cast<int>(entities.size());
}

// Curves that bound exactly one face, and the connected groups of faces (faces sharing a curve), of the synchronized
// model.
void open_edges_and_shells(SewingOutcome& outcome) {
  gmsh::vectorpair curves, faces;
  gmsh::model::getEntities(curves, 1);
  gmsh::model::getEntities(faces, 2);
  std::map<int, int> index;  // face tag -> its index, for the union-find below
  for (std::size_t k = 0; k < faces.size(); ++k) index[faces[k].second] = static_cast<int>(k);
  std::vector<int> parent(faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> root = [&](int k) { return parent[k] == k ? k : parent[k] = root(parent[k]); };
  outcome.free_edges = 0;
  for (const auto& [dim, tag] : curves) {
    std::vector<int> up, down;
    gmsh::model::getAdjacencies(dim, tag, up, down);
    if (up.size() == 1) ++outcome.free_edges;
    for (std::size_t k = 1; k < up.size(); ++k) {
      const auto a = index.find(up[0]), b = index.find(up[k]);
      if (a != index.end() && b != index.end()) parent[root(a->second)] = root(b->second);
    }
  }
  outcome.shells = 0;
  for (std::size_t k = 0; k < faces.size(); ++k) outcome.shells += root(static_cast<int>(k)) == static_cast<int>(k);
}

}  // namespace

SewingOutcome sew_shells_into_solids(double tolerance) {
  SewingOutcome outcome;
  outcome.surfaces = count(2);
  {
    SilencedStdStreams quiet;
    try {
      gmsh::vectorpair healed;
      gmsh::model::occ::healShapes(healed, {}, tolerance, /*fixDegenerated=*/true, /*fixSmallEdges=*/true,
                                   /*fixSmallFaces=*/true, /*sewFaces=*/true, /*makeSolids=*/true);
      gmsh::model::occ::synchronize();
    } catch (const std::string&) {  // healing failed: the model is as it was, and the attempt below may still work
      gmsh::model::occ::synchronize();
    }
    outcome.by_healing = count(3) > 0;
    if (!outcome.by_healing) {
      gmsh::vectorpair faces;
      gmsh::model::getEntities(faces, 2);
      std::vector<int> tags;
      for (const auto& [dim, tag] : faces) tags.push_back(tag);
      try {
        const int loop = gmsh::model::occ::addSurfaceLoop(tags, -1, /*sewing=*/true);
        gmsh::model::occ::addVolume({loop});
        gmsh::model::occ::synchronize();
      } catch (const std::string&) {
        gmsh::model::occ::synchronize();
      }
    }
  }
  outcome.solids = count(3);
  open_edges_and_shells(outcome);
  return outcome;
}

}  // namespace flexbody::preprocess::detail
