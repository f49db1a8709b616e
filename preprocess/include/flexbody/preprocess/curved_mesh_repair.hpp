#pragma once
// flexbody/preprocess/curved_mesh_repair.hpp: folded quadratic tetrahedra, found and straightened.
//
// A quadratic mesh's mid-edge nodes on curved CAD surfaces can fold an element (det ∂x/∂ξ <= 0 somewhere inside it)
// where a small fillet or a thin feature bends an edge across its neighbours. gmsh's elastic smoothing of the
// high-order nodes cures many of these (gmsh_import.cpp runs it first); what it leaves is straightened here: the mid-edge nodes of a folded
// element move to the midpoints of their edges' corners. A straight-sided tetrahedron with a positive volume has a
// constant positive Jacobian, so each round cures the element it straightens, and a neighbour that a moved node
// folds in turn is straightened in the next round: the loop ends, at the latest, with the linear mesh's geometry.

#include "flexbody/preprocess/tet_mesh.hpp"

#include <vector>

namespace flexbody::preprocess {

/// The elements whose Jacobian determinant is not positive (or not finite) at a Gauss point or a node
/// (format::tet10_jacobian_determinants), in element order.
[[nodiscard]] std::vector<Eigen::Index> folded_elements(const Tet10Mesh& mesh);

struct Straightening {
  int elements = 0;            ///< folded elements straightened, over all rounds
  int nodes = 0;               ///< mid-edge nodes moved onto their edges
  int rounds = 0;              ///< passes over the folded elements (a moved node can fold a neighbour)
  double largest_move_m = 0.0; ///< the largest distance a node moved: the geometry's largest local change [m]
};

/// Straightens the folded elements' edges until no element is folded. Throws std::runtime_error if the corners' own
/// tetrahedra are not all positive (then no straightening can help; check_element_volumes says which).
Straightening straighten_folded_elements(Tet10Mesh& mesh);

}  // namespace flexbody::preprocess
