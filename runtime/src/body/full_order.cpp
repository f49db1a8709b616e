#include "flexbody/runtime/full_order.hpp"

#include "full_order_mesh.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

namespace flexbody::runtime {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using FieldMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// The sparse body with fields Ῡ' = T (empty: I) of the mesh's K̄ and M_s (both triangles stored).
BodyModel sparse_body(const SparseMatrix& stiffness, const SparseMatrix& scalar_mass, const FieldMatrix& fields,
                      const format::RowMatrixX3d& nodes, const std::string& source) {
  const Eigen::Index n_n = nodes.rows();
  if (scalar_mass.rows() != n_n || scalar_mass.cols() != n_n || stiffness.rows() != 3 * n_n || stiffness.cols() != 3 * n_n)
    throw std::invalid_argument(source + ": K must be 3 n_n square and M_s n_n square for " + std::to_string(n_n) + " nodes");
  // Both triangles stored: the sparse Cholesky reads one, the products read both (an upper triangle alone, as the
  // assembly stores it, would be silently wrong).
  for (const SparseMatrix* m : {&stiffness, &scalar_mass}) {
    const SparseMatrix transposed = m->transpose();
    if ((*m - transposed).norm() > 1e-12 * m->norm())
      throw std::invalid_argument(source + ": K and M_s must be symmetric with both triangles stored");
  }
  auto blocks = std::make_shared<SparseFieldBlocks>();
  // Y = [Y_r, T] with Y_r = [1, X̄]: G = Yᵀ M_s Y (Eq. 66 with Ῡ' = T) has the dense border rows
  // [Y_rᵀ M_s Y_r, Y_rᵀ M_s T] and the sparse field block Tᵀ M_s T; K̂ = (T ⊗ I3)ᵀ K̄ (T ⊗ I3) (Eq. 96).
  Eigen::MatrixXd y_r(n_n, 4);
  y_r << Eigen::VectorXd::Ones(n_n), nodes;
  const Eigen::MatrixXd m_y = scalar_mass * y_r;  // n_n x 4
  Eigen::Index n_f = n_n;
  if (fields.rows() == 0) {
    blocks->mass = scalar_mass;
    blocks->stiffness = stiffness;
  } else {
    n_f = fields.cols();
    const SparseMatrix t = fields;
    std::vector<Eigen::Triplet<double>> entries;  // T ⊗ I3
    entries.reserve(static_cast<std::size_t>(3 * t.nonZeros()));
    for (Eigen::Index c = 0; c < t.outerSize(); ++c)
      for (SparseMatrix::InnerIterator it(t, c); it; ++it)
        for (int d = 0; d < 3; ++d) entries.emplace_back(3 * it.row() + d, 3 * it.col() + d, it.value());
    SparseMatrix expanded(3 * n_n, 3 * n_f);
    expanded.setFromTriplets(entries.begin(), entries.end());
    // Symmetric to the last bit: the Cholesky reads one triangle, the products read both.
    const SparseMatrix mass = t.transpose() * scalar_mass * t;
    const SparseMatrix k = expanded.transpose() * stiffness * expanded;
    blocks->mass = 0.5 * (mass + SparseMatrix(mass.transpose()));
    blocks->stiffness = 0.5 * (k + SparseMatrix(k.transpose()));
    blocks->fields = fields;
  }
  blocks->border.resize(4, 4 + n_f);
  blocks->border.leftCols<4>() = y_r.transpose() * m_y;
  if (fields.rows() == 0) blocks->border.rightCols(n_f) = m_y.transpose();
  else blocks->border.rightCols(n_f) = (fields.transpose() * m_y).transpose();
  BodyModel model;
  model.source = source;
  model.mass = blocks->border(0, 0);
  if (blocks->border.block<1, 3>(0, 1).norm() > 1e-9 * model.mass * std::max(1.0, nodes.cwiseAbs().maxCoeff()))
    throw std::invalid_argument(source + ": the nodes must be in the body frame (centre of mass at the origin)");
  model.tisserand = blocks->border.block(1, 4, 3, n_f);
  model.nodes = nodes;
  model.mode_coefficients.resize(n_f, 0);
  model.sparse = std::move(blocks);
  return model;
}

}  // namespace

BodyModel full_order_model(const SparseMatrix& stiffness, const SparseMatrix& scalar_mass,
                           const format::RowMatrixX3d& nodes, const std::string& source) {
  return sparse_body(stiffness, scalar_mass, FieldMatrix(), nodes, source);
}

BodyModel full_order_model(const format::BodyData& body, const std::string& source) {
  const format::BodyMesh& mesh = body.mesh;
  if (mesh.element_order != 1 && mesh.element_order != 2)
    throw std::invalid_argument(source + ": the full-order body needs linear or quadratic tetrahedra (element order " +
                                std::to_string(mesh.element_order) + ")");
  if (mesh.tets.cols() != format::BodyMesh::nodes_per_element(mesh.element_order))
    throw std::invalid_argument(source + ": element order " + std::to_string(mesh.element_order) + " with " +
                                std::to_string(mesh.tets.cols()) + " nodes per tetrahedron");
  const format::Material& material = body.material;
  if (!(material.youngs_modulus > 0.0) || !(material.density > 0.0) || !(material.poisson_ratio > -1.0) ||
      !(material.poisson_ratio < 0.5))
    throw std::invalid_argument(source + ": the full-order body needs the material's E > 0, rho > 0 and -1 < nu < 0.5");
  const Eigen::Index n_n = mesh.nodes.rows();
  const auto outside = [n_n](Eigen::Index i) { return i < 0 || i >= n_n; };
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
    for (Eigen::Index a = 0; a < mesh.tets.cols(); ++a)
      if (outside(mesh.tets(e, a)))
        throw std::invalid_argument(source + ": tetrahedron " + std::to_string(e) + " names node " +
                                    std::to_string(mesh.tets(e, a)) + ", outside the mesh's " + std::to_string(n_n));
  for (const format::Interface& i : body.interfaces)
    for (const int node : i.nodes)
      if (outside(node))
        throw std::invalid_argument(source + ": interface '" + i.name + "' names node " + std::to_string(node) +
                                    ", outside the mesh's " + std::to_string(n_n));
  const AssembledMesh fe = assemble_mesh(mesh, material, source);
  for (Eigen::Index i = 0; i < n_n; ++i)  // a node of no element has no mass and no stiffness: a singular body
    if (!(fe.scalar_mass.coeff(i, i) > 0.0))
      throw std::invalid_argument(source + ": node " + std::to_string(i) + " belongs to no tetrahedron");
  const FieldMatrix fields = affine_node_sets(mesh.nodes, body.interfaces, source);
  BodyModel model = sparse_body(fe.stiffness, fe.scalar_mass, fields, mesh.nodes, source);
  model.surface_triangles = mesh.surface_triangles;
  for (const format::Interface& i : body.interfaces) model.interfaces.push_back(full_order_interface(i, model, source));
  return model;
}

BodyModel damp_full_order(BodyModel model, double beta) {
  if (!model.sparse) throw std::invalid_argument(model.source + ": damp_full_order needs the full-order body");
  if (!(beta >= 0.0) || !std::isfinite(beta))
    throw std::invalid_argument(model.source + ": stiffness-proportional damping needs beta >= 0");
  auto blocks = std::make_shared<SparseFieldBlocks>(*model.sparse);
  blocks->stiffness_damping = beta;
  model.sparse = std::move(blocks);
  return model;
}

}  // namespace flexbody::runtime
