#include "flexbody/format/tet4_element.hpp"

#include <Eigen/Dense>

namespace flexbody::format {

Tet4Geometry tet4_geometry(const Eigen::Matrix<double, 4, 3>& corners) {
  // x = x0 + J xi with J = [x1 - x0, x2 - x0, x3 - x0]; N_a = xi_a (a = 1..3), N_0 = 1 - sum xi.
  Eigen::Matrix3d jacobian;
  for (int a = 0; a < 3; ++a) jacobian.col(a) = (corners.row(a + 1) - corners.row(0)).transpose();
  const double det = jacobian.determinant();
  Tet4Geometry g;
  g.volume = det / 6.0;
  if (det == 0.0) return g;
  // grad N_a (a = 1..3) is row a-1 of J^-1.
  const Eigen::Matrix3d inverse = jacobian.inverse();
  g.gradients.bottomRows<3>() = inverse;
  g.gradients.row(0) = -inverse.colwise().sum();
  return g;
}

Eigen::Matrix3d tet4_stiffness_block(const Tet4Geometry& geometry, int b, int a, double lambda, double mu) {
  const Eigen::RowVector3d gb = geometry.gradients.row(b);
  const Eigen::RowVector3d ga = geometry.gradients.row(a);
  Eigen::Matrix3d block = lambda * gb.transpose() * ga + mu * ga.transpose() * gb;
  block.diagonal().array() += mu * gb.dot(ga);
  return geometry.volume * block;
}

double tet4_mass_entry(double density, double volume, int a, int b, MassScheme scheme) {
  const double m = density * volume;
  switch (scheme) {
    case MassScheme::consistent: return m / 20.0 * (a == b ? 2.0 : 1.0);
    case MassScheme::lumped: return a == b ? m / 4.0 : 0.0;
    case MassScheme::one_point: return m / 16.0;
  }
  return 0.0;
}

}  // namespace flexbody::format
