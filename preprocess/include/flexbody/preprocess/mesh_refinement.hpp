#pragma once
// flexbody/preprocess/mesh_refinement.hpp: element sizes for a second mesh, refined where the error estimate
// (error_estimate.hpp) puts the frequencies' error (the default mesh resolves the part).
//
// An element e of size h_e (here (8.5 V_e)^(1/3), the size at which gmsh fills its volume V_e: gmsh_import.cpp's
// estimate) holds the share η²_e of a mode's relative eigenvalue error. With elements of order p and a smooth mode,
// remeshing its region at h'_e = s_e h_e leaves η²_e s_e^(2p) there in s_e^(-3) elements. The fewest elements for a
// total share T (a Lagrange multiplier on Σ s_e^(-3) subject to Σ η²_e s_e^(2p) = T) put s_e ∝ η_e^(-2/(2p+3)): the
// error is equidistributed (Zienkiewicz and Zhu 1987's remeshing, on the eigenvalue error). The factor of
// proportionality is found by bisection; the sizes are bounded by [finest, 1] × h_e (refine only, and at most so far
// in one pass), and the element count by a budget, which wins over the target.

#include "flexbody/preprocess/tet_mesh.hpp"

#include <Eigen/Core>

namespace flexbody::preprocess {

/// gmsh's nearly regular tetrahedra of edge h fill a volume V with about kTetrahedraPerCubedSize V / h³ of them (the
/// import's estimate of a mesh before it is made, and element_sizes' inverse of it).
inline constexpr double kTetrahedraPerCubedSize = 8.5;

struct RefinementRequest {
  int order = 2;                  ///< the element order p of the mesh the shares come from
  double target_share = 0.0;      ///< the total relative eigenvalue error Σ_e η²_e s_e^(2p) to reach (dimensionless)
  double finest = 0.25;           ///< the smallest s_e: no element shrinks by more than this in one pass
  double max_elements = 0.0;      ///< the budget of tetrahedra Σ_e s_e^(-3) (corner elements)
};

struct RefinementPlan {
  Eigen::VectorXd sizes;              ///< h'_e = s_e h_e per element of the mesh the shares come from [its unit]
  double predicted_elements = 0.0;    ///< Σ_e s_e^(-3): the new mesh's tetrahedra, as gmsh fills the sizes
  double predicted_share = 0.0;       ///< Σ_e η²_e s_e^(2p): the total share the new mesh should be left with
  bool budget_bound = false;          ///< the element budget, not the target, set the sizes
};

/// Each element's size (8.5 V_e)^(1/3) of the corner mesh (its unit).
[[nodiscard]] Eigen::VectorXd element_sizes(const TetMesh& mesh);

/// The sizes that reach request.target_share with the fewest elements, within the bounds (above). `shares` are the
/// elements' η²_e (FrequencyErrorEstimate::element_shares), `sizes` their h_e (element_sizes). Throws
/// std::invalid_argument for sizes and shares of different lengths, a non-positive or non-finite size, a negative or
/// non-finite share, an order other than 1 or 2, a target not positive, finest outside (0, 1], or a budget below the
/// elements there are.
[[nodiscard]] RefinementPlan plan_refinement(const Eigen::VectorXd& sizes, const Eigen::VectorXd& shares,
                                             const RefinementRequest& request);

}  // namespace flexbody::preprocess
