#include "flexbody/preprocess/stress_recovery.hpp"

#include "flexbody/format/tet10_element.hpp"
#include "flexbody/preprocess/tet4_element.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace flexbody::preprocess {
namespace {

// Output nodes are processed in chunks of this many: a task builds the chunk's averaged-gradient operators, then
// applies them column by column, so each column's output rows of a chunk are contiguous in memory and the
// operators (~15 neighbours per node) stay in cache while every column passes through.
constexpr Eigen::Index kChunk = 256;
constexpr std::int64_t kNoElement = std::numeric_limits<std::int64_t>::max();

// Node-to-element incidence (compressed rows), elements ascending for each node.
struct Incidence {
  std::vector<std::int64_t> start;     // n_n + 1 offsets
  std::vector<std::int32_t> elements;  // (nodes per element) n_e element indices
};

// Nodes per element of a mesh type.
template <class Mesh>
constexpr int kNodesPerElement = std::is_same_v<Mesh, Tet10Mesh> ? 10 : 4;

// What one element gives the node at its local position `local`: the element's volume (<= 0: inverted or folded)
// and the gradient weights of its nodes at that node, row b: ∇u = Σ_b u_b ⊗ gradients.row(b). Linear tetrahedra: the
// constant gradients; quadratic ones: the gradients extrapolated from the Gauss points (format/tet10_element.hpp).
template <class Mesh>
struct ElementAtNode {
  double volume = 0.0;
  Eigen::Matrix<double, kNodesPerElement<Mesh>, 3> gradients;
};

ElementAtNode<TetMesh> element_at_node(const TetMesh& mesh, Eigen::Index e, int /*local*/) {
  const Tet4Geometry geometry = tet4_geometry(element_corners(mesh, e));
  return {geometry.volume, geometry.gradients};
}

ElementAtNode<Tet10Mesh> element_at_node(const Tet10Mesh& mesh, Eigen::Index e, int local) {
  format::Tet10Nodes x;
  for (int a = 0; a < 10; ++a) x.row(a) = mesh.nodes.row(mesh.tets(e, a));
  const format::Tet10RecoveryGradients g = format::tet10_recovery_gradients(x);
  return {g.volume, g.at_node[static_cast<std::size_t>(local)]};
}

std::string element_problem(const TetMesh& mesh, Eigen::Index e) {
  return fmt::format("tetrahedron {} has volume {} m^3 (inverted or degenerate)", e,
                     tet4_geometry(element_corners(mesh, e)).volume);
}

std::string element_problem(const Tet10Mesh& /*mesh*/, Eigen::Index e) {
  return fmt::format("quadratic tetrahedron {} is inverted or folded (its Jacobian determinant is not positive at a "
                     "Gauss point)", e);
}

// Checks the mesh (finite coordinates, node indices in range) and returns its incidence.
template <class Mesh>
Incidence checked_incidence(const Mesh& mesh, const char* function) {
  constexpr int per = kNodesPerElement<Mesh>;
  const Eigen::Index n_n = mesh.node_count(), n_e = mesh.element_count();
  if (!mesh.nodes.allFinite())
    for (Eigen::Index i = 0; i < n_n; ++i)
      if (!mesh.nodes.row(i).allFinite())
        throw std::invalid_argument(fmt::format("{}: mesh node {} has a non-finite coordinate", function, i));
  if (n_e > std::numeric_limits<std::int32_t>::max())
    throw std::invalid_argument(fmt::format("{}: the mesh has {} elements, more than 2^31 - 1", function, n_e));
  Incidence incidence;
  incidence.start.assign(static_cast<std::size_t>(n_n) + 1, 0);
  for (Eigen::Index e = 0; e < n_e; ++e)
    for (int a = 0; a < per; ++a) {
      const std::int32_t i = mesh.tets(e, a);
      if (i < 0 || i >= n_n)
        throw std::invalid_argument(
            fmt::format("{}: tetrahedron {} refers to node {}, the mesh has {} nodes", function, e, i, n_n));
      ++incidence.start[static_cast<std::size_t>(i) + 1];
    }
  for (Eigen::Index i = 0; i < n_n; ++i) incidence.start[i + 1] += incidence.start[i];
  incidence.elements.resize(static_cast<std::size_t>(incidence.start.back()));
  std::vector<std::int64_t> fill(incidence.start.begin(), incidence.start.end() - 1);
  for (Eigen::Index e = 0; e < n_e; ++e)
    for (int a = 0; a < per; ++a) incidence.elements[fill[mesh.tets(e, a)]++] = static_cast<std::int32_t>(e);
  return incidence;
}

template <class Mesh>
void check_output_nodes(const Mesh& mesh, const Incidence& incidence, const Eigen::VectorXi& nodes,
                        const char* function) {
  for (Eigen::Index j = 0; j < nodes.size(); ++j) {
    const int i = nodes(j);
    if (i < 0 || i >= mesh.node_count())
      throw std::invalid_argument(fmt::format("{}: region node {} (entry {}) is out of range, the mesh has {} nodes",
                                              function, i, j, mesh.node_count()));
    if (incidence.start[i + 1] == incidence.start[i])
      throw std::invalid_argument(fmt::format("{}: node {} belongs to no element", function, i));
  }
}

void check_finite(const Eigen::MatrixXd& values, const char* function, const char* what) {
  if (values.allFinite()) return;
  for (Eigen::Index c = 0; c < values.cols(); ++c)
    for (Eigen::Index r = 0; r < values.rows(); ++r)
      if (!std::isfinite(values(r, c)))
        throw std::invalid_argument(fmt::format("{}: {}({}, {}) is {}", function, what, r, c, values(r, c)));
}

// The volume-averaged gradient operators of a chunk of output nodes: output node j of the chunk has the
// entries [start[j], start[j + 1]), each a neighbour b (the node itself included) and
// w_jb = Σ_{e ∋ j, b} V_e ∇N_b^e / Σ_{e ∋ j} V_e [1/m], so the averaged gradient of a scalar field υ is Σ_b υ_b w_jb.
struct ChunkOperators {
  std::vector<std::int64_t> start;
  std::vector<std::int32_t> node;
  std::vector<Eigen::Vector3d> weight;

  // Builds the operators of output_nodes(begin .. end - 1); returns the smallest element around them whose
  // volume is not positive (those are skipped), or kNoElement.
  template <class Mesh>
  std::int64_t build(const Mesh& mesh, const Incidence& incidence, const Eigen::VectorXi& output_nodes,
                     Eigen::Index begin, Eigen::Index end) {
    constexpr int per = kNodesPerElement<Mesh>;
    start.assign(1, 0);
    node.clear();
    weight.clear();
    std::int64_t bad = kNoElement;
    for (Eigen::Index j = begin; j < end; ++j) {
      const int i = output_nodes(j);
      const std::size_t first = node.size();
      double total_volume = 0.0;
      for (std::int64_t s = incidence.start[i]; s < incidence.start[i + 1]; ++s) {
        const std::int32_t e = incidence.elements[s];
        int local = 0;
        while (mesh.tets(e, local) != i) ++local;
        const ElementAtNode<Mesh> element = element_at_node(mesh, e, local);
        if (!(element.volume > 0.0)) {
          bad = std::min<std::int64_t>(bad, e);
          continue;
        }
        total_volume += element.volume;
        for (int a = 0; a < per; ++a) {
          const std::int32_t b = mesh.tets(e, a);
          std::size_t k = first;
          while (k < node.size() && node[k] != b) ++k;
          if (k == node.size()) {
            node.push_back(b);
            weight.emplace_back(Eigen::Vector3d::Zero());
          }
          weight[k] += element.volume * element.gradients.row(a).transpose();
        }
      }
      for (std::size_t k = first; k < node.size(); ++k) weight[k] /= total_volume;
      start.push_back(static_cast<std::int64_t>(node.size()));
    }
    return bad;
  }
};

// Runs apply(operators, begin, end) for every chunk of output nodes in parallel (each output row is written by
// the one task that owns its chunk, in a fixed order: results independent of the thread count), then throws if
// an element around an output node has a non-positive volume.
template <class Mesh, typename Apply>
void for_each_chunk(const Mesh& mesh, const Incidence& incidence, const Eigen::VectorXi& output_nodes,
                    const char* function, Apply&& apply) {
  const Eigen::Index chunks = (output_nodes.size() + kChunk - 1) / kChunk;
  std::int64_t bad = kNoElement;
#pragma omp parallel reduction(min : bad)
  {
    ChunkOperators operators;
#pragma omp for schedule(dynamic, 1)
    for (Eigen::Index chunk = 0; chunk < chunks; ++chunk) {
      const Eigen::Index begin = chunk * kChunk, end = std::min(begin + kChunk, output_nodes.size());
      bad = std::min(bad, operators.build(mesh, incidence, output_nodes, begin, end));
      apply(operators, begin, end);
    }
  }
  if (bad != kNoElement) throw std::invalid_argument(fmt::format("{}: {}", function, element_problem(mesh, bad)));
}

// Writes one Voigt stress vector at `out`.
void put(double* out, const std::array<double, kStressComponents>& stress) { std::copy(stress.begin(), stress.end(), out); }

}  // namespace

namespace {

template <class Mesh>
Eigen::MatrixXd stresses_of(const Mesh& mesh, const Material& material, const Eigen::MatrixXd& displacements) {
  static constexpr const char* kFunction = "nodal_stresses";
  check_material(material);
  const Incidence incidence = checked_incidence(mesh, kFunction);
  if (displacements.rows() != mesh.dof_count())
    throw std::invalid_argument(fmt::format("{}: displacements has {} rows, expected 3 n_n = {} (x, y, z per node)",
                                            kFunction, displacements.rows(), mesh.dof_count()));
  check_finite(displacements, kFunction, "displacements");
  const Eigen::VectorXi all_nodes = Eigen::VectorXi::LinSpaced(mesh.node_count(), 0, static_cast<int>(mesh.node_count()) - 1);
  check_output_nodes(mesh, incidence, all_nodes, kFunction);

  const double lambda = lame_lambda(material), mu = shear_modulus(material);
  Eigen::MatrixXd stresses(kStressComponents * mesh.node_count(), displacements.cols());
  for_each_chunk(mesh, incidence, all_nodes, kFunction, [&](const ChunkOperators& op, Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index column = 0; column < displacements.cols(); ++column) {
      const double* u = displacements.col(column).data();
      double* out = stresses.col(column).data();
      for (Eigen::Index j = begin; j < end; ++j) {
        // Averaged displacement gradient H(r, c) = ∂u_r/∂x_c, then ε = ½ (H + Hᵀ) and σ = λ tr(ε) I + 2 μ ε.
        Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
        for (std::int64_t k = op.start[j - begin]; k < op.start[j - begin + 1]; ++k) {
          const double* ub = u + 3 * static_cast<std::int64_t>(op.node[k]);
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) h(r, c) += ub[r] * op.weight[k](c);
        }
        const double trace = h(0, 0) + h(1, 1) + h(2, 2);
        double* s = out + kStressComponents * j;
        s[0] = lambda * trace + 2.0 * mu * h(0, 0);
        s[1] = lambda * trace + 2.0 * mu * h(1, 1);
        s[2] = lambda * trace + 2.0 * mu * h(2, 2);
        s[3] = mu * (h(0, 1) + h(1, 0));
        s[4] = mu * (h(0, 2) + h(2, 0));
        s[5] = mu * (h(1, 2) + h(2, 1));
      }
    }
  });
  return stresses;
}

template <class Mesh>
Eigen::MatrixXd stress_modes_of(const Mesh& mesh, const Material& material, const Eigen::MatrixXd& fields,
                                const Eigen::VectorXi& region_nodes) {
  static constexpr const char* kFunction = "nodal_stress_modes";
  check_material(material);
  const Incidence incidence = checked_incidence(mesh, kFunction);
  if (fields.rows() != mesh.node_count())
    throw std::invalid_argument(fmt::format("{}: fields has {} rows, expected one per node ({})", kFunction,
                                            fields.rows(), mesh.node_count()));
  check_finite(fields, kFunction, "fields");
  check_output_nodes(mesh, incidence, region_nodes, kFunction);

  const double lambda = lame_lambda(material), mu = shear_modulus(material);
  Eigen::MatrixXd modes(kStressComponents * region_nodes.size(), 3 * fields.cols());
  for_each_chunk(mesh, incidence, region_nodes, kFunction, [&](const ChunkOperators& op, Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index f = 0; f < fields.cols(); ++f) {
      const double* v = fields.col(f).data();
      double* out_x = modes.col(3 * f).data();
      double* out_y = modes.col(3 * f + 1).data();
      double* out_z = modes.col(3 * f + 2).data();
      for (Eigen::Index j = begin; j < end; ++j) {
        Eigen::Vector3d g = Eigen::Vector3d::Zero();  // averaged gradient of the field
        for (std::int64_t k = op.start[j - begin]; k < op.start[j - begin + 1]; ++k) g += v[op.node[k]] * op.weight[k];
        // Displacement υ e_d: H = e_d gᵀ, ε_ij = ½ (δ_id g_j + δ_jd g_i), tr ε = g_d; each entry is written the
        // way nodal_stresses evaluates it for that H (λ tr ε + 2 μ H_dd, μ (H_ij + H_ji)).
        const Eigen::Index row = kStressComponents * j;
        const double lx = lambda * g.x(), ly = lambda * g.y(), lz = lambda * g.z();
        put(out_x + row, {lx + 2.0 * mu * g.x(), lx, lx, mu * g.y(), mu * g.z(), 0.0});
        put(out_y + row, {ly, ly + 2.0 * mu * g.y(), ly, mu * g.x(), 0.0, mu * g.z()});
        put(out_z + row, {lz, lz, lz + 2.0 * mu * g.z(), 0.0, mu * g.x(), mu * g.y()});
      }
    }
  });
  return modes;
}

}  // namespace

Eigen::MatrixXd nodal_stresses(const TetMesh& mesh, const Material& material, const Eigen::MatrixXd& displacements) {
  return stresses_of(mesh, material, displacements);
}

Eigen::MatrixXd nodal_stresses(const Tet10Mesh& mesh, const Material& material, const Eigen::MatrixXd& displacements) {
  return stresses_of(mesh, material, displacements);
}

Eigen::MatrixXd nodal_stress_modes(const TetMesh& mesh, const Material& material, const Eigen::MatrixXd& fields,
                                   const Eigen::VectorXi& region_nodes) {
  return stress_modes_of(mesh, material, fields, region_nodes);
}

Eigen::MatrixXd nodal_stress_modes(const Tet10Mesh& mesh, const Material& material, const Eigen::MatrixXd& fields,
                                   const Eigen::VectorXi& region_nodes) {
  return stress_modes_of(mesh, material, fields, region_nodes);
}

double von_mises(const Eigen::Matrix<double, 6, 1>& s) {
  const double normal = (s(0) - s(1)) * (s(0) - s(1)) + (s(1) - s(2)) * (s(1) - s(2)) + (s(2) - s(0)) * (s(2) - s(0));
  const double shear = s(3) * s(3) + s(4) * s(4) + s(5) * s(5);
  return std::sqrt(0.5 * normal + 3.0 * shear);
}

}  // namespace flexbody::preprocess
