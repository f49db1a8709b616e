#pragma once
// flexbody/format/tet10_element.hpp: the quadratic tetrahedron (10 nodes), beside the linear one
// (tet4_element.hpp) for the same reason: fbprep assembles K̄ and M_s from it and the runtime's full-order body would
// assemble them again from a body file's mesh.
//
// Node order (Abaqus C3D10, VTK_QUADRATIC_TETRA): the corners 0-3, then the mid-edge nodes of the edges (0,1), (1,2),
// (2,0), (0,3), (1,3), (2,3). (gmsh's 10-node tetrahedron lists the last two edges the other way round, (2,3) before
// (1,3): its meshes are reordered on import.) With barycentric coordinates L_0 = 1 − ξ_1 − ξ_2 − ξ_3, L_k = ξ_k:
// N_i = L_i (2 L_i − 1) at a corner, N_ij = 4 L_i L_j at the middle of edge (i, j). The geometry is isoparametric:
// x(ξ) = Σ_a N_a(ξ) x_a, so mid-edge nodes off their edge's middle curve the element.

#include <Eigen/Core>

#include <array>

namespace flexbody::format {

using Tet10Nodes = Eigen::Matrix<double, 10, 3>;  ///< one element's node coordinates, one row per node [m]

/// The corners of each mid-edge node 4..9.
inline constexpr std::array<std::array<int, 2>, 6> kTet10Edges{{{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}};

/// The 30 x 30 stiffness of an isotropic linear-elastic element [N/m], node-interleaved (row 3a + r: node a,
/// direction r), by the 4-point Gauss rule of degree 2: exact for a straight-sided element (constant Jacobian, strains
/// linear), Abaqus' rule for C3D10 otherwise.
[[nodiscard]] Eigen::Matrix<double, 30, 30> tet10_stiffness(const Tet10Nodes& nodes, double lambda, double mu);

/// How the consistent mass ρ ∫ N_a N_b dV is integrated.
enum class Tet10MassRule {
  /// A collapsed 5 x 5 x 5 Gauss product rule (degree 9 in each direction): exact for straight-sided elements and for
  /// curved ones, whose Jacobian determinant is cubic.
  exact,
  /// The stiffness's 4-point rule of degree 2, which N_a N_b (degree 4) exceeds: what CalculiX's C3D10 does
  /// (tests/preprocess/calculix_test.cpp), for comparing like with like.
  four_point,
};

/// The scalar consistent mass ρ ∫ N_a N_b dV (10 x 10) [kg]; the vector mass is this ⊗ I3.
[[nodiscard]] Eigen::Matrix<double, 10, 10> tet10_mass(const Tet10Nodes& nodes, double density,
                                                       Tet10MassRule rule = Tet10MassRule::exact);

/// The Jacobian determinant det ∂x/∂ξ at the 4 Gauss points, then at the 10 nodes [m³ per unit reference volume,
/// 6 V for a straight element]: an element whose values are not all positive is inverted or folded by its
/// curvature (the quality check).
[[nodiscard]] Eigen::Matrix<double, 14, 1> tet10_jacobian_determinants(const Tet10Nodes& nodes);

/// The 4-point Gauss rule of degree 2 on the reference tetrahedron (volume 1/6), the rule of tet10_stiffness: its
/// points ξ, each of weight kTet10GaussWeight (∫ f dV ≈ Σ_g kTet10GaussWeight det J(ξ_g) f(ξ_g)).
[[nodiscard]] std::array<Eigen::Vector3d, 4> tet10_gauss_points();
inline constexpr double kTet10GaussWeight = 1.0 / 24.0;

/// The shape functions' gradients ∂N_a/∂x (row a, 1/m) and det ∂x/∂ξ at reference point ξ (for stress recovery).
struct Tet10Gradients {
  Eigen::Matrix<double, 10, 3> gradients = Eigen::Matrix<double, 10, 3>::Zero();
  double determinant = 0.0;
};
[[nodiscard]] Tet10Gradients tet10_gradients(const Tet10Nodes& nodes, const Eigen::Vector3d& xi);

/// What stress recovery uses of one element: the displacement gradient at each of its nodes, extrapolated
/// from the 4 Gauss points as Abaqus and CalculiX do, ∇u(node a) = Σ_b u_b ⊗ at_node[a].row(b). The 4 Gauss-point
/// values are fitted by the linear function of the barycentric coordinates through them and that function is
/// evaluated at the node (at a mid-edge node: the mean of its two corners). In a straight-sided element the gradient
/// is linear, so this is the exact gradient at the node; in a curved one it is the usual extrapolation.
struct Tet10RecoveryGradients {
  std::array<Eigen::Matrix<double, 10, 3>, 10> at_node{};  ///< at_node[a](b, k) = extrapolated ∂N_b/∂x_k [1/m]
  double volume = 0.0;  ///< Σ_g w_g det J_g [m³] (the 4-point rule: exact for straight-sided elements)
};
/// Throws nothing; volume <= 0 marks an element whose Jacobian is not positive at a Gauss point (at_node then zero).
[[nodiscard]] Tet10RecoveryGradients tet10_recovery_gradients(const Tet10Nodes& nodes);

}  // namespace flexbody::format
