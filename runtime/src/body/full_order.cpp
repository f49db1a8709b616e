#include "flexbody/runtime/full_order.hpp"

#include <stdexcept>

namespace flexbody::runtime {

BodyModel full_order_model(const Eigen::MatrixXd& stiffness, const Eigen::MatrixXd& scalar_mass,
                           const format::RowMatrixX3d& nodes, const std::string& source) {
  const Eigen::Index n_n = nodes.rows();
  if (scalar_mass.rows() != n_n || scalar_mass.cols() != n_n || stiffness.rows() != 3 * n_n || stiffness.cols() != 3 * n_n)
    throw std::invalid_argument(source + ": K must be 3 n_n square and M_s n_n square for " + std::to_string(n_n) + " nodes");
  // Y = [1, X̄, I]: G = Yᵀ M_s Y (Eq. 66 with Ῡ = I).
  Eigen::MatrixXd y(n_n, 4 + n_n);
  y << Eigen::VectorXd::Ones(n_n), nodes, Eigen::MatrixXd::Identity(n_n, n_n);
  BodyModel model;
  model.source = source;
  model.mass_matrix = y.transpose() * scalar_mass * y;
  model.mass = model.mass_matrix(0, 0);
  if (model.mass_matrix.row(0).segment<3>(1).norm() > 1e-9 * model.mass * std::max(1.0, nodes.cwiseAbs().maxCoeff()))
    throw std::invalid_argument(source + ": the nodes must be in the body frame (centre of mass at the origin)");
  model.stiffness = stiffness;
  model.tisserand = model.mass_matrix.block(1, 4, 3, n_n);
  model.fields = Eigen::MatrixXd::Identity(n_n, n_n);
  model.nodes = nodes;
  model.mode_coefficients.resize(n_n, 0);
  return model;
}

}  // namespace flexbody::runtime
