#include "full_order_mesh.hpp"

#include "flexbody/format/tet10_element.hpp"
#include "flexbody/format/tet4_element.hpp"

#include <Eigen/Dense>

#include <stdexcept>

namespace flexbody::runtime {
namespace {

// K̄ (3 n_n square) and M_s (n_n square) summed from their element triplets.
AssembledMesh from_triplets(Eigen::Index n_n, const std::vector<Eigen::Triplet<double>>& k_entries,
                            const std::vector<Eigen::Triplet<double>>& m_entries) {
  AssembledMesh out;
  out.stiffness.resize(3 * n_n, 3 * n_n);
  out.stiffness.setFromTriplets(k_entries.begin(), k_entries.end());
  out.scalar_mass.resize(n_n, n_n);
  out.scalar_mass.setFromTriplets(m_entries.begin(), m_entries.end());
  return out;
}

// K̄ and M_s of quadratic tetrahedra: fbprep's element integrals (format/tet10_element.hpp; the exact consistent mass,
// as preprocess/tet10_assembly.hpp), both triangles.
AssembledMesh assemble_quadratic(const format::BodyMesh& mesh, const format::Material& material, double lambda,
                                 double mu, const std::string& source) {
  const Eigen::Index n_n = mesh.nodes.rows(), n_e = mesh.tets.rows();
  std::vector<Eigen::Triplet<double>> k_entries, m_entries;
  k_entries.reserve(static_cast<std::size_t>(900 * n_e));
  m_entries.reserve(static_cast<std::size_t>(100 * n_e));
  for (Eigen::Index t = 0; t < n_e; ++t) {
    format::Tet10Nodes x;
    for (int a = 0; a < 10; ++a) x.row(a) = mesh.nodes.row(mesh.tets(t, a));
    if (!(format::tet10_jacobian_determinants(x).minCoeff() > 0.0))
      throw std::invalid_argument(source + ": quadratic tetrahedron " + std::to_string(t) + " is inverted or folded "
                                  "(its Jacobian determinant is not positive at every Gauss point and node)");
    const Eigen::Matrix<double, 30, 30> k = format::tet10_stiffness(x, lambda, mu);
    const Eigen::Matrix<double, 10, 10> m = format::tet10_mass(x, material.density);
    for (int b = 0; b < 10; ++b)
      for (int a = 0; a < 10; ++a) {
        const Eigen::Index row = mesh.tets(t, b), col = mesh.tets(t, a);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) k_entries.emplace_back(3 * row + r, 3 * col + c, k(3 * b + r, 3 * a + c));
        m_entries.emplace_back(row, col, m(b, a));
      }
  }
  return from_triplets(n_n, k_entries, m_entries);
}

}  // namespace

AssembledMesh assemble_mesh(const format::BodyMesh& mesh, const format::Material& material, const std::string& source) {
  const double e = material.youngs_modulus, nu = material.poisson_ratio;
  const double lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu = e / (2.0 * (1.0 + nu));  // Lamé's parameters
  if (mesh.element_order == 2) return assemble_quadratic(mesh, material, lambda, mu, source);
  const Eigen::Index n_n = mesh.nodes.rows(), n_e = mesh.tets.rows();
  std::vector<Eigen::Triplet<double>> k_entries, m_entries;
  k_entries.reserve(static_cast<std::size_t>(144 * n_e));
  m_entries.reserve(static_cast<std::size_t>(16 * n_e));
  for (Eigen::Index t = 0; t < n_e; ++t) {
    Eigen::Matrix<double, 4, 3> corners;
    for (int a = 0; a < 4; ++a) corners.row(a) = mesh.nodes.row(mesh.tets(t, a));
    const format::Tet4Geometry g = format::tet4_geometry(corners);
    if (!(g.volume > 0.0))
      throw std::invalid_argument(source + ": tetrahedron " + std::to_string(t) + " is inverted or flat (volume " +
                                  std::to_string(g.volume) + " m^3)");
    for (int b = 0; b < 4; ++b)
      for (int a = 0; a < 4; ++a) {
        const Eigen::Index row = mesh.tets(t, b), col = mesh.tets(t, a);
        const Eigen::Matrix3d block = format::tet4_stiffness_block(g, b, a, lambda, mu);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) k_entries.emplace_back(3 * row + r, 3 * col + c, block(r, c));
        m_entries.emplace_back(row, col,
                               format::tet4_mass_entry(material.density, g.volume, a, b, format::MassScheme::consistent));
      }
  }
  return from_triplets(n_n, k_entries, m_entries);
}

Eigen::SparseMatrix<double, Eigen::RowMajor> affine_node_sets(const format::RowMatrixX3d& nodes,
                                                              const std::vector<format::Interface>& interfaces,
                                                              const std::string& source) {
  const Eigen::Index n_n = nodes.rows();
  std::vector<int> owner(static_cast<std::size_t>(n_n), -1);
  bool any = false;
  for (std::size_t k = 0; k < interfaces.size(); ++k) {
    if (interfaces[k].coupling != "rbe2") continue;
    any = true;
    for (const int i : interfaces[k].nodes) {
      int& o = owner[static_cast<std::size_t>(i)];
      if (o >= 0)
        throw std::invalid_argument(source + ": rbe2 interfaces '" + interfaces[static_cast<std::size_t>(o)].name + "' and '" +
                                    interfaces[k].name + "' share node " + std::to_string(i));
      o = static_cast<int>(k);
    }
  }
  if (!any) return {};
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::Index column = 0;
  for (Eigen::Index i = 0; i < n_n; ++i)
    if (owner[static_cast<std::size_t>(i)] < 0) entries.emplace_back(i, column++, 1.0);
  for (const format::Interface& set : interfaces) {
    if (set.coupling != "rbe2") continue;
    const Eigen::Index k = set.nodes.size();
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (Eigen::Index j = 0; j < k; ++j) centre += nodes.row(set.nodes(j)).transpose() / static_cast<double>(k);
    Eigen::MatrixXd basis(k, 4);  // [1, (X̄ − X̄_c)/ρ] over the set
    for (Eigen::Index j = 0; j < k; ++j) {
      basis(j, 0) = 1.0;
      basis.block<1, 3>(j, 1) = nodes.row(set.nodes(j)) - centre.transpose();
    }
    const double radius = basis.rightCols<3>().rowwise().norm().maxCoeff();
    if (radius > 0.0) basis.rightCols<3>() /= radius;
    // The independent columns, chosen by column-pivoted QR: a flat set's normal coordinate is round-off of its
    // radius, so its pivot falls below 1e-10 of the largest (flat meshed faces are flat to ~1e-15 of their size).
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(basis);
    qr.setThreshold(1e-10);
    const Eigen::Index rank = qr.rank();
    for (Eigen::Index c = 0; c < rank; ++c) {
      const Eigen::Index source_column = qr.colsPermutation().indices()(c);
      for (Eigen::Index j = 0; j < k; ++j)
        if (basis(j, source_column) != 0.0) entries.emplace_back(set.nodes(j), column, basis(j, source_column));
      ++column;
    }
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> t(n_n, column);
  t.setFromTriplets(entries.begin(), entries.end());
  return t;
}

format::Interface full_order_interface(const format::Interface& interface, const BodyModel& model,
                                       const std::string& source) {
  format::Interface out = interface;
  const Eigen::Index n_f = model.field_count();
  out.y_row = Eigen::VectorXd::Zero(4 + n_f);
  for (Eigen::Index j = 0; j < interface.nodes.size(); ++j) {
    const double w = interface.weights(j);
    const Eigen::Index i = interface.nodes(j);
    out.y_row(0) += w;
    out.y_row.segment<3>(1) += w * model.nodes.row(i).transpose();
    out.y_row.tail(n_f) += w * field_row(model, i).transpose();
  }
  out.reference_point = out.y_row.segment<3>(1);
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd moments = Eigen::MatrixXd::Zero(3, 3 * n_f);  // Σ_i w_i Ῡ'_f(i) [d_i]×, per field f
  for (Eigen::Index j = 0; j < interface.nodes.size(); ++j) {
    const double w = interface.weights(j);
    const Eigen::Index i = interface.nodes(j);
    const Eigen::Vector3d d = model.nodes.row(i).transpose() - out.reference_point;
    h += w * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
    Eigen::Matrix3d s;
    s << 0, -d.z(), d.y(), d.z(), 0, -d.x(), -d.y(), d.x(), 0;
    const Eigen::RowVectorXd row = field_row(model, i);
    for (Eigen::Index f = 0; f < n_f; ++f)
      if (row(f) != 0.0) moments.middleCols<3>(3 * f) += (w * row(f)) * s;
  }
  const Eigen::Vector3d principal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(h).eigenvalues();
  if (!(principal(0) > 1e-10 * principal(2)))
    throw std::invalid_argument(source + ": interface '" + interface.name + "': its nodes lie on a line");
  out.rotation = h.ldlt().solve(moments);
  return out;
}

}  // namespace flexbody::runtime
