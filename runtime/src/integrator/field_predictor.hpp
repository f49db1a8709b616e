#pragma once
// The predictor of GCMS bodies' fields at steps that do not resolve them (GeneralizedAlpha::predict; not installed).
//
// generalized-α's predictor q̈_{n+1} = q̈_n carries a field component of frequency ω by about (ω h)² times its
// oscillation's amplitude, and a GCMS body's generalized basis reaches far above its kept modes (formulations.md, "The
// Method": the fields' spectrum: 1e5 Hz for a beam whose modes end at 2 kHz). The Newton matrix built at such a
// predictor couples the rotation to the fields through K̂ ξ̄ (Eq. (86)) as if the body were deformed thousands of times
// more than it is. Here each body's field space is split by the eigenvectors of (K̂, G_ff ⊗ I3): the components the step
// resolves, ω h ≤ 1, keep the constant-acceleration predictor (second order: starting them elsewhere left a resolved
// vibration two iterations whose stopping test misjudged, and its energy error grew 500-fold); those it does not keep
// the deformation of the last step, seen in the body frame (ξ̄ held, turned with the predicted rotation). Full-order
// bodies keep the constant-acceleration predictor (their K̄ has no eigenbasis at this cost).

#include "flexbody/runtime/system.hpp"

#include <Eigen/Core>

#include <memory>
#include <vector>

namespace flexbody::runtime::detail {

class FieldPredictor {
 public:
  /// Decomposes every GCMS body's (K̂, G_ff ⊗ I3) (bodies with equal matrices share one decomposition): O((3 n_f)³)
  /// per distinct part, once.
  explicit FieldPredictor(const System& system);
  /// The split for steps of size h [s]: the components with ω h > 1 are held.
  void set_step(double h);
  /// Whether the body whose coordinates start at `offset` is split here (a GCMS body with a definite (K̂, G_ff ⊗ I3)).
  [[nodiscard]] bool splits(Eigen::Index offset) const;
  /// The split bodies' components' ω² [1/s²], ascending, one vector per split body in the order of the system.
  [[nodiscard]] std::vector<const Eigen::VectorXd*> frequencies() const;
  /// The largest nodal displacement [m] that a change x of the coordinates makes in the first `measured[k]`
  /// components of the k-th split body (the slowest), over its fields: max over fields f of
  /// |(V_r V_rᵀ (G ⊗ I3) Âᵀ x_ξ)_f| / reach_f (Â from q; reach_f the field's scale per metre, 1 / max_i |Ῡ'(i, f)|).
  /// The error control's measure of the fields (local_error.hpp).
  [[nodiscard]] double displacement(const Eigen::VectorXd& q, const Eigen::VectorXd& x, const Eigen::VectorXd& reach,
                                    const std::vector<Eigen::Index>& measured);
  /// q_pred (the constant-acceleration predictor of every coordinate) with each GCMS body's unresolved field
  /// components moved to the last step's deformation (q_n's), turned with q_pred's rotation:
  /// ξ ← ξ + Â_p V_s V_sᵀ (G ⊗ I3) (Â_nᵀ ξ_n − Â_p⁻¹ ξ). `moved(first, count)` is called for each range of
  /// coordinates it changed. No allocation after the first step at a step size.
  template <class Moved>
  void apply(const Eigen::VectorXd& q_n, Eigen::VectorXd& q_pred, Moved&& moved) {
    for (Body& body : bodies_)
      if (hold(body, q_n, q_pred)) moved(body.offset + 12, 3 * body.fields);
  }

 private:
  struct Basis {
    Eigen::MatrixXd vectors;   ///< V: (K̂, G ⊗ I3)'s eigenvectors, Vᵀ (G ⊗ I3) V = I, by ascending ω²
    Eigen::MatrixXd weighted;  ///< Vᵀ (G ⊗ I3)
    Eigen::VectorXd omega2;    ///< ω² [1/s²], ascending
  };
  struct Body {
    Eigen::Index offset = 0, fields = 0;
    std::shared_ptr<const Basis> basis;
    Eigen::Index stiff_from = 0;  ///< the first held component at the current step
    Eigen::VectorXd difference, components;  ///< work vectors
  };
  static bool hold(Body& body, const Eigen::VectorXd& q_n, Eigen::VectorXd& q_pred);
  std::vector<Body> bodies_;
};

}  // namespace flexbody::runtime::detail
