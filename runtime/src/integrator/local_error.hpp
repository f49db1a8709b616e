#pragma once
// generalized-α's local error estimate (GeneralizedAlphaOptions::error_tolerance; not installed).
//
// With a_n ≈ q̈(t_n + (α_m − α_f) h) (second order), one step of the Newmark update from exact q_n, v_n moves the
// positions by h v + h²/2 q̈ + h³ (β + (α_m − α_f)/2) q⃛ where the exact motion moves them by h v + h²/2 q̈ + h³/6 q⃛;
// a_{n+1} − a_n = h q⃛ + O(h²), so the step's position error is
//   e = (β − γ/2 + 1/12) h² (a_{n+1} − a_n)   (γ = ½ + α_f − α_m; 1/12 at ρ∞ = 1, the trapezoidal rule's),
// taken here over two steps, h q⃛ ≈ h (a_{n+1} − a_{n−1}) / (h + h_{n−1}): a vibration the step does not resolve
// decays in generalized-α as (−ρ∞)ⁿ (its roots tend to −ρ∞ as ω h → ∞), alternating from step to step, and the
// difference over two steps keeps (1 − ρ∞²)/2 of what one step's keeps (0.1 at ρ∞ = 0.9). With one step's, the
// bracket pendulum's estimate at 1e-8 m jumped by 5x from step to step with its pivot force's alternation (the
// bracket's 2-8 kHz modes excited at the start), and the controller changed the step at 4 steps in 5 (with the
// two-step difference 2 470 Newton matrices in 3 131 steps; with the filter as well, 236 in 733).
// GeneralizedAlpha filters that vector through its Newton matrix (estimate_step_error), and it is then
// measured here in metres, each coordinate by its reach (the world displacement per unit of it, as Newton's stopping
// test scales it: 1 for τ, A's entries and Euler parameters at the body's radius of gyration, a field component or
// a mode at its largest nodal displacement), the largest over the coordinates. Measuring a GCMS body's τ and A by
// the rigid motion that best fits their displacement field instead (A's symmetric part is an affine deformation)
// made no difference worth its code once the filter was in: the bracket pendulum at 1e-8 m took 733 steps and 236
// Newton matrices with it, 768 and 270 without, to the same error (9.2e-6 m). A flexible body's vibrations that the step
// does not resolve are not measured: generalized-α damps them (ρ∞ < 1) and they follow their loads
// quasi-statically; measuring them would shrink the step until it resolved frequencies the scene does not ask for.
// So a GCMS body's field components (field_predictor.hpp's eigenvectors of (K̂, G_ff ⊗ I3)) and a floating-frame
// body's modes (ω² the Rayleigh quotient K_ff(k,k) / M_ff(k,k)) count only while the step resolves them; the
// full-order body has no such split and is refused. Whether a vibration counts changes with hysteresis, from
// ω h ≤ 1 at the first step: one that counts stops counting above ω h = 2, one that does not starts below ω h = ½,
// so that a step near a component's ω h = 1 does not flip between counting it (shrinking) and not (growing); that
// reason is an argument, not a measurement. The filter already divides what the step does not resolve by about
// β (ω h)², so the split adds little: counting every component and mode took the bracket pendulum at 1e-8 m 752
// steps with the GCMS (768 with the split) and 803 with the FFRF (692 with it), to the same error.

#include "field_predictor.hpp"

#include "flexbody/runtime/system.hpp"

#include <Eigen/Core>

#include <vector>

namespace flexbody::runtime::detail {

class LocalError {
 public:
  /// `reach`: per coordinate, its scale per metre (GeneralizedAlpha's reach_); `coefficient`: β − γ/2 + 1/12.
  /// `splitter`: the integrator's field predictor, whose split of the GCMS bodies' fields is used. Throws
  /// std::invalid_argument for a full-order body.
  LocalError(const System& system, const Eigen::VectorXd& reach, double coefficient, const FieldPredictor& splitter);
  /// The vibrations counted at steps of size h [s] (floating-frame modes and GCMS field components), with the
  /// hysteresis the header describes.
  void set_step(double h);
  /// Which vibrations count (they depend on the steps taken so far), for a checkpoint; restore() takes it back.
  [[nodiscard]] std::vector<double> state() const;
  void restore(const std::vector<double>& state);  ///< throws std::invalid_argument for one of another system
  /// The estimate's vector (in the coordinates) of a step of size h that ends with a_{n+1} = `a_to`, from `a_from`,
  /// a's value `span` seconds earlier (a_n: span = h; a_{n−1}: span = h + h_{n−1}).
  void estimate(const Eigen::VectorXd& a_from, const Eigen::VectorXd& a_to, double h, double span,
                Eigen::VectorXd& out) const;
  /// An error vector e's size [m] at q (the step's end), as the header says.
  [[nodiscard]] double measure(const Eigen::VectorXd& q, const Eigen::VectorXd& e, FieldPredictor& fields) const;

 private:
  struct Modes {
    Eigen::Index first = 0;  ///< the coordinate of the body's first mode
    Eigen::VectorXd omega2;  ///< per mode, K_ff(k,k) / M_ff(k,k) [1/s²]
  };
  /// Whether a vibration of ω² counts at steps of h, having counted (`counted`) or not; `first`: no step before.
  [[nodiscard]] static bool counts(double omega2, double h, bool counted, bool first);
  double coefficient_;
  Eigen::VectorXd reach_;
  Eigen::VectorXd weight_;  ///< per coordinate: 1 / reach where measured directly, 0 where not (or split elsewhere)
  std::vector<Modes> modes_;
  std::vector<const Eigen::VectorXd*> field_frequencies_;  ///< per body FieldPredictor splits, its ω², ascending
  std::vector<Eigen::Index> fields_counted_;  ///< per such body, how many of its slowest components count
  bool stepped_ = false;  ///< set_step was called
};

}  // namespace flexbody::runtime::detail
