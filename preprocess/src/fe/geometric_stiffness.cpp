#include "flexbody/preprocess/geometric_stiffness.hpp"

#include "flexbody/format/tet10_element.hpp"
#include "flexbody/format/tet4_element.hpp"
#include "flexbody/preprocess/assembly.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace flexbody::preprocess {
namespace {

// σ = λ tr(ε) I + 2 μ ε of the displacement gradient h (h(i, j) = ∂u_i/∂x_j).
Eigen::Matrix3d stress_of(const Eigen::Matrix3d& h, double lambda, double mu) {
  const Eigen::Matrix3d strain = 0.5 * (h + h.transpose());
  return lambda * strain.trace() * Eigen::Matrix3d::Identity() + 2.0 * mu * strain;
}

void check_load_case_sizes(const char* what, Eigen::Index nodes, const Material& material,
                           const Eigen::MatrixXd& displacements, const Eigen::MatrixXd& fields) {
  if (displacements.rows() != 3 * nodes || fields.rows() != nodes)
    throw std::invalid_argument(fmt::format("geometric stiffness ({}): {} nodes, but displacements of {} rows (3 per "
                                            "node) and fields of {} rows", what, nodes, displacements.rows(),
                                            fields.rows()));
  if (!displacements.allFinite() || !fields.allFinite())
    throw std::invalid_argument(fmt::format("geometric stiffness ({}): a displacement or a field is not finite", what));
  check_material(material);
}

// Σ over the elements of w Tᵀ σ T, T = ∇Nᵀ Y_e (3 x c) at each integration point, one matrix per displacement
// column. `points(e, visit)` calls visit(weight, gradients (n_e x 3), nodes of e) for each integration point of e.
template <int PerElement, typename Tets, typename Points>
std::vector<Eigen::MatrixXd> project(const Tets& tets, const Material& material, const Eigen::MatrixXd& displacements,
                                     const Eigen::MatrixXd& fields, Points&& points) {
  const double lambda = lame_lambda(material), mu = shear_modulus(material);
  const Eigen::Index cases = displacements.cols(), c = fields.cols();
  std::vector<Eigen::MatrixXd> result(static_cast<std::size_t>(cases));
#pragma omp parallel for schedule(dynamic, 1)
  for (Eigen::Index k = 0; k < cases; ++k) {
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(c, c);
    Eigen::MatrixXd t(3, c), st(3, c);
    for (Eigen::Index e = 0; e < tets.rows(); ++e) {
      points(e, [&](double weight, const Eigen::Matrix<double, PerElement, 3>& gradients) {
        Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
        t.setZero();
        for (int a = 0; a < PerElement; ++a) {
          const Eigen::Index node = tets(e, a);
          h.noalias() += displacements.block<3, 1>(3 * node, k) * gradients.row(a);
          t.noalias() += gradients.row(a).transpose() * fields.row(node);
        }
        st.noalias() = stress_of(h, lambda, mu) * t;
        sum.noalias() += weight * t.transpose() * st;
      });
    }
    result[static_cast<std::size_t>(k)] = 0.5 * (sum + sum.transpose());
  }
  return result;
}

}  // namespace

Eigen::MatrixXd centrifugal_unit_loads(const RowMatrixX3d& body_nodes, const SparseMatrix& scalar_mass_upper) {
  const Eigen::Index n = body_nodes.rows();
  if (scalar_mass_upper.rows() != n || scalar_mass_upper.cols() != n)
    throw std::invalid_argument(fmt::format("centrifugal loads: {} nodes, but a {} x {} mass matrix", n,
                                            scalar_mass_upper.rows(), scalar_mass_upper.cols()));
  Eigen::MatrixXd accelerations(3 * n, 6), loads(3 * n, 6);
  for (std::size_t k = 0; k < kCentrifugalCases.size(); ++k) {
    const int i = kCentrifugalCases[k][0] - 'x', j = kCentrifugalCases[k][1] - 'x';
    Eigen::Matrix3d w = Eigen::Matrix3d::Zero();
    w(i, j) = 1.0;
    w(j, i) = 1.0;  // e_i e_iᵀ for i = j, e_i e_jᵀ + e_j e_iᵀ otherwise
    const Eigen::Matrix3d field = w.trace() * Eigen::Matrix3d::Identity() - w;  // the force per unit mass is field x̄
    for (Eigen::Index a = 0; a < n; ++a)
      accelerations.block<3, 1>(3 * a, static_cast<Eigen::Index>(k)) = field * body_nodes.row(a).transpose();
  }
  for (Eigen::Index k = 0; k < 6; ++k) apply_vector_mass(scalar_mass_upper, accelerations.col(k), loads.col(k));
  return loads;
}

std::vector<Eigen::MatrixXd> projected_geometric_stiffness(const TetMesh& mesh, const Material& material,
                                                           const Eigen::MatrixXd& displacements,
                                                           const Eigen::MatrixXd& fields) {
  check_load_case_sizes("linear tetrahedra", mesh.node_count(), material, displacements, fields);
  const std::vector<Tet4Geometry> geometry = element_geometries(mesh);
  return project<4>(mesh.tets, material, displacements, fields, [&](Eigen::Index e, auto&& visit) {
    const Tet4Geometry& g = geometry[static_cast<std::size_t>(e)];  // constant strain: one point, exact
    visit(g.volume, g.gradients);
  });
}

std::vector<Eigen::MatrixXd> projected_geometric_stiffness(const Tet10Mesh& mesh, const Material& material,
                                                           const Eigen::MatrixXd& displacements,
                                                           const Eigen::MatrixXd& fields) {
  check_load_case_sizes("quadratic tetrahedra", mesh.node_count(), material, displacements, fields);
  const std::array<Eigen::Vector3d, 4> rule = format::tet10_gauss_points();
  return project<10>(mesh.tets, material, displacements, fields, [&](Eigen::Index e, auto&& visit) {
    format::Tet10Nodes corners;
    for (int a = 0; a < 10; ++a) corners.row(a) = mesh.nodes.row(mesh.tets(e, a));
    for (const Eigen::Vector3d& xi : rule) {  // the 4-point rule of K̄ (tet10_element.hpp)
      const format::Tet10Gradients g = format::tet10_gradients(corners, xi);
      visit(format::kTet10GaussWeight * g.determinant, g.gradients);
    }
  });
}

}  // namespace flexbody::preprocess
