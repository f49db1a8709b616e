#pragma once
// flexbody/format/tet4_element.hpp: the linear tetrahedron (4 nodes, constant strain) of a body file's mesh
// (SCHEMA.md /mesh, element_order 1). It lives with the file format because two libraries integrate that mesh:
// fbprep assembles K̄ and M_s from it (preprocess/assembly.hpp), and the runtime's full-order reference body
// assembles them again from the file's mesh and material (runtime/full_order.hpp), so both must mean the same
// element.

#include <Eigen/Core>

namespace flexbody::format {

/// Geometry of one linear tetrahedron: signed volume and the constant gradients of its four shape
/// functions (row a = grad N_a, 1/m).
struct Tet4Geometry {
  double volume = 0.0;
  Eigen::Matrix<double, 4, 3> gradients = Eigen::Matrix<double, 4, 3>::Zero();
};

/// Volume and shape-function gradients of the tetrahedron with corner coordinates x0..x3 (rows).
/// The volume is signed: negative for an inverted element, then the gradients are still exact.
[[nodiscard]] Tet4Geometry tet4_geometry(const Eigen::Matrix<double, 4, 3>& corners);

/// The 3x3 stiffness block coupling node b (rows) with node a (columns):
/// K_ba[r][c] = V (lambda g_b[r] g_a[c] + mu g_b[c] g_a[r] + mu delta_rc g_b.g_a),
/// the standard isotropic small-strain element integral (constant strain, exact with one point).
[[nodiscard]] Eigen::Matrix3d tet4_stiffness_block(const Tet4Geometry& geometry, int b, int a,
                                                   double lambda, double mu);

/// Scalar element mass schemes. The vector mass of an element is M_s,e ⊗ I3.
enum class MassScheme {
  consistent,  ///< exact integral of rho N_a N_b: rho V / 20 (1 + delta_ab)
  lumped,      ///< row-sum lumping of the consistent mass: rho V / 4 on the diagonal (Abaqus C3D4)
  one_point,   ///< one-point quadrature at the centroid, rho V / 16 in every entry (CalculiX C3D4)
};

/// Entry (a, b) of the scalar element mass matrix [kg] for the given scheme.
[[nodiscard]] double tet4_mass_entry(double density, double volume, int a, int b, MassScheme scheme);

}  // namespace flexbody::format
