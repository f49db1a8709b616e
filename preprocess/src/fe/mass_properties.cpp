#include "flexbody/preprocess/mass_properties.hpp"

namespace flexbody::preprocess {

format::MassProperties mass_properties(const SparseMatrix& scalar_mass_upper, const RowMatrixX3d& nodes) {
  const Eigen::Index n = nodes.rows();
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(n);
  const Eigen::VectorXd m_ones = scalar_mass_upper.selfadjointView<Eigen::Upper>() * ones;  // M_s 1
  format::MassProperties props;
  props.mass = m_ones.sum();
  props.center_of_mass_input = (nodes.transpose() * m_ones) / props.mass;
  // Second moments about the centre of mass: J = (X - 1 c^T)^T M_s (X - 1 c^T).
  const RowMatrixX3d centred = nodes.rowwise() - props.center_of_mass_input.transpose();
  const RowMatrixX3d m_centred = scalar_mass_upper.selfadjointView<Eigen::Upper>() * centred;
  Eigen::Matrix3d second_moments = centred.transpose() * m_centred;
  second_moments = 0.5 * (second_moments + second_moments.transpose()).eval();
  props.inertia_about_com = second_moments.trace() * Eigen::Matrix3d::Identity() - second_moments;
  return props;
}

}  // namespace flexbody::preprocess
