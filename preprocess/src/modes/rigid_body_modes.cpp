#include "flexbody/preprocess/rigid_body_modes.hpp"

#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/mass_properties.hpp"

#include <Eigen/Dense>

#include <stdexcept>

namespace flexbody::preprocess {

Eigen::MatrixXd rigid_body_modes(const RowMatrixX3d& nodes, const SparseMatrix& scalar_mass_upper) {
  const Eigen::Index n = nodes.rows();
  const Eigen::RowVector3d centre = mass_properties(scalar_mass_upper, nodes).center_of_mass_input.transpose();
  Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(3 * n, 6);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d x = (nodes.row(i) - centre).transpose();
    for (int k = 0; k < 3; ++k) {
      modes(3 * i + k, k) = 1.0;  // translation along axis k
      // small rotation about axis k: e_k x x
      const Eigen::Vector3d rotation = Eigen::Vector3d::Unit(k).cross(x);
      modes.block<3, 1>(3 * i, 3 + k) = rotation;
    }
  }
  // M̄-orthonormalize: R <- R L^-T with L Lᵀ = Rᵀ M̄ R.
  Eigen::MatrixXd mass_modes(3 * n, 6);
  for (int k = 0; k < 6; ++k) apply_vector_mass(scalar_mass_upper, modes.col(k), mass_modes.col(k));
  const Eigen::MatrixXd gram = modes.transpose() * mass_modes;
  Eigen::LLT<Eigen::MatrixXd> llt(gram);
  if (llt.info() != Eigen::Success)
    throw std::runtime_error("rigid-body modes: the mass matrix is singular on the rigid-body fields");
  const Eigen::MatrixXd lower = llt.matrixL();
  return lower.triangularView<Eigen::Lower>().solve(modes.transpose()).transpose();
}

}  // namespace flexbody::preprocess
