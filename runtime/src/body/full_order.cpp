#include "flexbody/runtime/full_order.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>

namespace flexbody::runtime {

BodyModel full_order_model(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& scalar_mass,
                           const format::RowMatrixX3d& nodes, const std::string& source) {
  const Eigen::Index n_n = nodes.rows();
  if (scalar_mass.rows() != n_n || scalar_mass.cols() != n_n || stiffness.rows() != 3 * n_n || stiffness.cols() != 3 * n_n)
    throw std::invalid_argument(source + ": K must be 3 n_n square and M_s n_n square for " + std::to_string(n_n) + " nodes");
  // Both triangles stored: the sparse Cholesky reads one, the products read both (an upper triangle alone, as the
  // assembly stores it, would be silently wrong).
  for (const Eigen::SparseMatrix<double>* m : {&stiffness, &scalar_mass}) {
    const Eigen::SparseMatrix<double> transposed = m->transpose();
    if ((*m - transposed).norm() > 1e-12 * m->norm())
      throw std::invalid_argument(source + ": K and M_s must be symmetric with both triangles stored");
  }
  // Y = [Y_r, I] with Y_r = [1, X̄]: G = Yᵀ M_s Y (Eq. 66 with Ῡ = I) has the dense border rows
  // [Y_rᵀ M_s Y_r, Y_rᵀ M_s] and the sparse field block M_s.
  Eigen::MatrixXd y_r(n_n, 4);
  y_r << Eigen::VectorXd::Ones(n_n), nodes;
  const Eigen::MatrixXd m_y = scalar_mass * y_r;  // n_n x 4
  auto blocks = std::make_shared<SparseFieldBlocks>();
  blocks->mass = scalar_mass;
  blocks->stiffness = stiffness;
  blocks->border.resize(4, 4 + n_n);
  blocks->border.leftCols<4>() = y_r.transpose() * m_y;
  blocks->border.rightCols(n_n) = m_y.transpose();
  BodyModel model;
  model.source = source;
  model.mass = blocks->border(0, 0);
  if (blocks->border.block<1, 3>(0, 1).norm() > 1e-9 * model.mass * std::max(1.0, nodes.cwiseAbs().maxCoeff()))
    throw std::invalid_argument(source + ": the nodes must be in the body frame (centre of mass at the origin)");
  model.tisserand = blocks->border.block(1, 4, 3, n_n);
  model.nodes = nodes;
  model.mode_coefficients.resize(n_n, 0);
  model.sparse = std::move(blocks);
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
