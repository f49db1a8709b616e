#include "flexbody/preprocess/mesh_topology.hpp"

#include "flexbody/format/tet10_element.hpp"
#include "flexbody/preprocess/tet4_element.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace flexbody::preprocess {
namespace {

std::int32_t find_root(std::vector<std::int32_t>& parent, std::int32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// Faces opposite each corner, ordered so that their normal points away from that corner for a
// positively oriented tetrahedron.
constexpr std::array<std::array<int, 3>, 4> kFaces = {{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};

}  // namespace

MeshComponents connected_components(const TetMesh& mesh) {
  const auto n = static_cast<std::int32_t>(mesh.node_count());
  std::vector<std::int32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> used(n, 0);
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e) {
    const std::int32_t root = find_root(parent, mesh.tets(e, 0));
    for (int a = 0; a < 4; ++a) {
      used[mesh.tets(e, a)] = 1;
      parent[find_root(parent, mesh.tets(e, a))] = root;
    }
  }
  MeshComponents result;
  result.node_component.assign(n, -1);
  std::vector<std::int32_t> label(n, -1);
  for (std::int32_t i = 0; i < n; ++i) {
    if (!used[i]) continue;
    const std::int32_t root = find_root(parent, i);
    if (label[root] < 0) label[root] = result.count++;
    result.node_component[i] = label[root];
  }
  return result;
}

std::vector<std::int32_t> remove_unused_nodes(TetMesh& mesh) {
  std::vector<std::int32_t> new_index(mesh.node_count(), -1);
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e)
    for (int a = 0; a < 4; ++a) new_index[mesh.tets(e, a)] = 0;
  std::int32_t next = 0;
  for (auto& index : new_index)
    if (index == 0) index = next++;
  if (next == mesh.node_count()) return new_index;
  RowMatrixX3d nodes(next, 3);
  for (Eigen::Index i = 0; i < mesh.node_count(); ++i)
    if (new_index[i] >= 0) nodes.row(new_index[i]) = mesh.nodes.row(i);
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e)
    for (int a = 0; a < 4; ++a) mesh.tets(e, a) = new_index[mesh.tets(e, a)];
  mesh.nodes = std::move(nodes);
  return new_index;
}

void check_element_volumes(const TetMesh& mesh, const std::string& source) {
  if (mesh.element_count() == 0) throw std::runtime_error(source + ": the mesh has no tetrahedra");
  // A volume below 1e-12 of the bounding box's volume is zero at double precision for any
  // reasonable mesh (the corners' coordinates carry ~1e-16 relative error each).
  const Eigen::RowVector3d extent = mesh.nodes.colwise().maxCoeff() - mesh.nodes.colwise().minCoeff();
  const double tiny = 1e-12 * extent.prod() / static_cast<double>(mesh.element_count());
  std::int64_t bad = 0;
  Eigen::Index first = -1;
  double first_volume = 0.0;
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e) {
    const double volume = tet4_geometry(element_corners(mesh, e)).volume;
    if (!(volume > tiny)) {
      if (bad++ == 0) {
        first = e;
        first_volume = volume;
      }
    }
  }
  if (bad > 0)
    throw std::runtime_error(source + ": " + std::to_string(bad) + " inverted or zero-volume element" +
                             (bad > 1 ? "s" : "") + ", first is tetrahedron " + std::to_string(first) +
                             fmt::format(" (0-based, volume {:.3g} m^3)", first_volume));
}

RowMatrixX3i boundary_triangles(const TetMesh& mesh) {
  struct Face {
    std::array<std::int32_t, 3> sorted;
    std::array<std::int32_t, 3> oriented;
  };
  std::vector<Face> faces;
  faces.reserve(4 * mesh.element_count());
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e)
    for (const auto& local : kFaces) {
      Face face;
      for (int k = 0; k < 3; ++k) face.oriented[k] = mesh.tets(e, local[k]);
      face.sorted = face.oriented;
      std::sort(face.sorted.begin(), face.sorted.end());
      faces.push_back(face);
    }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.sorted < b.sorted; });
  std::vector<std::array<std::int32_t, 3>> boundary;
  for (std::size_t k = 0; k < faces.size();) {
    std::size_t next = k + 1;
    while (next < faces.size() && faces[next].sorted == faces[k].sorted) ++next;
    if (next - k == 1) boundary.push_back(faces[k].oriented);
    k = next;
  }
  RowMatrixX3i triangles(static_cast<Eigen::Index>(boundary.size()), 3);
  for (std::size_t t = 0; t < boundary.size(); ++t)
    for (int k = 0; k < 3; ++k) triangles(static_cast<Eigen::Index>(t), k) = boundary[t][k];
  return triangles;
}

double radius_ratio(const Eigen::Matrix<double, 4, 3>& corners) {
  // r_in = 3V / (sum of face areas); r_circ from the circumcentre solve; q = 3 r_in / r_circ.
  const double volume = std::abs(tet4_geometry(corners).volume);
  if (volume == 0.0) return 0.0;
  double area = 0.0;
  for (const auto& f : kFaces) {
    const Eigen::Vector3d u = (corners.row(f[1]) - corners.row(f[0])).transpose();
    const Eigen::Vector3d v = (corners.row(f[2]) - corners.row(f[0])).transpose();
    area += 0.5 * u.cross(v).norm();
  }
  const double r_in = 3.0 * volume / area;
  Eigen::Matrix3d a;
  Eigen::Vector3d rhs;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d d = (corners.row(k + 1) - corners.row(0)).transpose();
    a.row(k) = 2.0 * d.transpose();
    rhs(k) = d.squaredNorm();
  }
  const double r_circ = a.partialPivLu().solve(rhs).norm();
  return std::clamp(3.0 * r_in / r_circ, 0.0, 1.0);
}

MeshQuality mesh_quality(const TetMesh& mesh) {
  MeshQuality q;
  q.min_radius_ratio = 1.0;
  q.min_edge_m = std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e) {
    const auto corners = element_corners(mesh, e);
    const double ratio = radius_ratio(corners);
    sum += ratio;
    if (ratio < q.min_radius_ratio) {
      q.min_radius_ratio = ratio;
      q.worst_element = e;
    }
    q.below_0_1 += ratio < 0.1;
    q.below_0_3 += ratio < 0.3;
    q.volume_m3 += tet4_geometry(corners).volume;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const double edge = (corners.row(a) - corners.row(b)).norm();
        q.min_edge_m = std::min(q.min_edge_m, edge);
        q.max_edge_m = std::max(q.max_edge_m, edge);
      }
  }
  q.mean_radius_ratio = mesh.element_count() > 0 ? sum / static_cast<double>(mesh.element_count()) : 0.0;
  return q;
}

std::array<std::array<std::int32_t, 3>, 4> split_quadratic_triangle(const std::array<std::int32_t, 6>& f) {
  return {{{f[0], f[3], f[5]}, {f[3], f[1], f[4]}, {f[5], f[4], f[2]}, {f[3], f[4], f[5]}}};
}

TetMesh corner_mesh(const Tet10Mesh& mesh) { return TetMesh{mesh.nodes, mesh.tets.leftCols<4>()}; }

RowMatrixX3i boundary_triangles(const Tet10Mesh& mesh) {
  // The corner faces on the boundary, then each edge's middle node (from any element that has the edge).
  const RowMatrixX3i faces = boundary_triangles(corner_mesh(mesh));
  auto key = [](std::int64_t i, std::int64_t j) { return i < j ? (i << 32) | j : (j << 32) | i; };
  std::unordered_map<std::int64_t, std::int32_t> middle;
  middle.reserve(static_cast<std::size_t>(3 * faces.rows()));
  for (Eigen::Index t = 0; t < faces.rows(); ++t)
    for (int k = 0; k < 3; ++k) middle.emplace(key(faces(t, k), faces(t, (k + 1) % 3)), -1);
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e)
    for (int k = 0; k < 6; ++k) {
      const auto [i, j] = format::kTet10Edges[static_cast<std::size_t>(k)];
      const auto it = middle.find(key(mesh.tets(e, i), mesh.tets(e, j)));
      if (it != middle.end()) it->second = mesh.tets(e, 4 + k);
    }
  RowMatrixX3i triangles(4 * faces.rows(), 3);
  for (Eigen::Index t = 0; t < faces.rows(); ++t) {
    std::array<std::int32_t, 6> face{};
    for (int k = 0; k < 3; ++k) {
      face[static_cast<std::size_t>(k)] = faces(t, k);
      face[static_cast<std::size_t>(3 + k)] = middle.at(key(faces(t, k), faces(t, (k + 1) % 3)));
    }
    const auto split = split_quadratic_triangle(face);
    for (int s = 0; s < 4; ++s)
      for (int k = 0; k < 3; ++k) triangles(4 * t + s, k) = split[static_cast<std::size_t>(s)][static_cast<std::size_t>(k)];
  }
  return triangles;
}

MeshQuality mesh_quality(const Tet10Mesh& mesh) {
  MeshQuality q = mesh_quality(corner_mesh(mesh));
  q.volume_m3 = 0.0;
  q.min_jacobian_ratio = 1.0;
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e) {
    format::Tet10Nodes x;
    for (int a = 0; a < 10; ++a) x.row(a) = mesh.nodes.row(mesh.tets(e, a));
    const Eigen::Matrix<double, 14, 1> det = format::tet10_jacobian_determinants(x);
    q.volume_m3 += det.head<4>().sum() / 24.0;  // the 4-point rule's weights, 1/24 each
    const double ratio = det.maxCoeff() > 0.0 ? det.minCoeff() / det.maxCoeff() : det.minCoeff();
    if (ratio < q.min_jacobian_ratio || q.worst_jacobian_element < 0) {
      q.min_jacobian_ratio = ratio;
      q.worst_jacobian_element = e;
    }
  }
  return q;
}

}  // namespace flexbody::preprocess
