#include "flexbody/preprocess/assembly.hpp"

#include <algorithm>
#include <stdexcept>

namespace flexbody::preprocess {

namespace {

template <class Mesh>
NodeGraph build_graph(const Mesh& mesh) {
  constexpr int per = static_cast<int>(decltype(mesh.tets)::ColsAtCompileTime);
  const std::int64_t n_nodes = mesh.node_count();
  const std::int64_t n_elements = mesh.element_count();
  NodeGraph graph;

  // Node-to-element incidence (CSR), entries in element order.
  graph.incidence_start.assign(n_nodes + 1, 0);
  for (std::int64_t e = 0; e < n_elements; ++e)
    for (int a = 0; a < per; ++a)
      if (mesh.tets(e, a) < 0 || mesh.tets(e, a) >= n_nodes)
        throw std::invalid_argument("mesh: tetrahedron " + std::to_string(e) + " refers to node " +
                                    std::to_string(mesh.tets(e, a)) + " of " + std::to_string(n_nodes));
  for (std::int64_t e = 0; e < n_elements; ++e)
    for (int a = 0; a < per; ++a) ++graph.incidence_start[mesh.tets(e, a) + 1];
  for (std::int64_t i = 0; i < n_nodes; ++i) {
    if (graph.incidence_start[i + 1] == 0)  // the assembly's column layout needs every node in an element
      throw std::invalid_argument("mesh: node " + std::to_string(i) + " belongs to no element (remove the unused nodes)");
    graph.incidence_start[i + 1] += graph.incidence_start[i];
  }
  graph.incidence.resize(graph.incidence_start.back());
  std::vector<std::int64_t> fill(graph.incidence_start.begin(), graph.incidence_start.end() - 1);
  for (std::int64_t e = 0; e < n_elements; ++e)
    for (int a = 0; a < per; ++a) graph.incidence[fill[mesh.tets(e, a)]++] = per * e + a;

  // Upper adjacency: neighbours i <= j of each node j, sorted and unique.
  std::vector<std::vector<std::int32_t>> neighbours(n_nodes);
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t j = 0; j < n_nodes; ++j) {
    auto& list = neighbours[j];
    for (std::int64_t k = graph.incidence_start[j]; k < graph.incidence_start[j + 1]; ++k) {
      const std::int64_t e = graph.incidence[k] / per;
      for (int b = 0; b < per; ++b)
        if (mesh.tets(e, b) <= j) list.push_back(mesh.tets(e, b));
    }
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  graph.column_start.assign(n_nodes + 1, 0);
  for (std::int64_t j = 0; j < n_nodes; ++j)
    graph.column_start[j + 1] = graph.column_start[j] + static_cast<std::int64_t>(neighbours[j].size());
  graph.rows.resize(graph.column_start.back());
  for (std::int64_t j = 0; j < n_nodes; ++j) {
    std::copy(neighbours[j].begin(), neighbours[j].end(), graph.rows.begin() + graph.column_start[j]);
    std::vector<std::int32_t>().swap(neighbours[j]);
  }
  return graph;
}

}  // namespace

NodeGraph NodeGraph::build(const TetMesh& mesh) { return build_graph(mesh); }
NodeGraph NodeGraph::build(const Tet10Mesh& mesh) { return build_graph(mesh); }

std::vector<Tet4Geometry> element_geometries(const TetMesh& mesh) {
  std::vector<Tet4Geometry> geometry(mesh.element_count());
#pragma omp parallel for schedule(static)
  for (std::int64_t e = 0; e < mesh.element_count(); ++e) geometry[e] = tet4_geometry(element_corners(mesh, e));
  return geometry;
}

SparseMatrix full_from_upper(const SparseMatrix& upper) {
  SparseMatrix full = upper.selfadjointView<Eigen::Upper>();
  full.makeCompressed();
  return full;
}

}  // namespace flexbody::preprocess
