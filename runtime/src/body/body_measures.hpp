#pragma once
// body_measures.hpp (internal): what the integrator measures on a body, in each formulation's own coordinates: the
// length scale of each coordinate (Newton's stopping test and the stabilised form's metric), the body's size, and the
// mass norm of its elastic displacement (the deformation limit).

#include "flexbody/runtime/body_model.hpp"
#include "flexbody/runtime/vector_ref.hpp"

#include <Eigen/Core>

namespace flexbody::runtime::detail {

/// The length scale [m per unit of the coordinate] of each of one body's coordinates (GeneralizedAlphaOptions::
/// tolerance), into `scales` (its coordinate_count() entries). With r = √(tr J / m) the radius of gyration: τ's is r;
/// vec(A)'s 1 (δa moves a point at distance r by r δa, as δτ = r δa would); the Euler parameters' ½ (δp turns the body
/// by 2 |δp|); a field coordinate's or a modal coordinate's, the amplitude whose largest nodal displacement is r
/// (r / max_i |Ῡ'(i, f)| for a field). The full-order body's fields are the nodal displacements themselves (Ῡ' = I) or
/// its rbe2 sets' affine fields, scaled to at most 1; a model built without its fields (or its nodes) takes the RMS
/// displacement, r √(m / G_ff(f, f)) (r √(m / M_mm) for a mode).
void coordinate_scales(const BodyModel& model, Eigen::Ref<Eigen::VectorXd> scales);

/// The bounding-box diagonal of the body's mesh [m]; 0 for a body without nodes (the integrator then has no size to
/// judge its deformation by; runtime::body_size, the initial assembly's, falls back on its radius of gyration).
[[nodiscard]] double mesh_diagonal(const BodyModel& model);

/// ∫|u|² dm of the body's elastic displacement [kg m²] at its coordinates q_b: ξ̄ᵀ (G_ff ⊗ I3) ξ̄, and |ξ̄| = |ξ| for an
/// orthogonal A, so without rotating. A floating-frame body's ξ̄ = Σ η_m c_m, its modes' field coordinates without the
/// rigid part an interface frame gives them (ηᵀ M_ff η would count that rigid motion as deformation: a rod in its
/// crank-end frame was stopped at "2 % RMS" while the same motion in the mean-axis frame was at 0.4 %).
[[nodiscard]] double elastic_mass_norm_squared(const BodyModel& model, const VectorRef& q_b);

/// elastic_mass_norm_squared, checked after every step: for a floating-frame body ηᵀ Γ η with Γ = Cᵀ (G_ff ⊗ I3) C
/// computed once (the same as ‖Σ η_k c_k‖², without a vector of 3 n_f doubles per step).
class ElasticMassNorm {
 public:
  explicit ElasticMassNorm(const BodyModel& model);
  [[nodiscard]] double squared(const VectorRef& q_b) const;

 private:
  const BodyModel* model_;
  Eigen::MatrixXd gram_;  ///< Γ (n_m square) of a floating-frame body; empty for the others
};

}  // namespace flexbody::runtime::detail
