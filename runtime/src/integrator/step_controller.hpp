#pragma once
// The step size of a run under error control (GeneralizedAlphaOptions::error_tolerance; not installed): a PI
// controller on generalized-α's local error estimate.
//
// The estimate is O(h³) (local_error.hpp), so the elementary controller h_new = h (E / e)^(1/3) would put the error
// at E; the PI controller of Gustafsson (1991) in the form of Hairer & Wanner (Solving ODEs II, IV.2, Eq. (2.43c))
// also weighs the last accepted error, which damps the step's oscillation where the error changes fast:
//   h_new = h · 0.9 · (E / e_n)^(0.7/3) · (e_{n−1} / E)^(0.4/3),   growth within [0.2, 2], none right after a rejection.
// The proposal follows every accepted step (a PI controller's small changes add up); how often the step taken changes
// is GeneralizedAlpha::step_toward's choice (a changed step costs new Newton cores: core_inverses.hpp).

#include <vector>

namespace flexbody::runtime::detail {

class StepController {
 public:
  /// `tolerance` [m], steps [s]: 0 < min_step <= first <= max_step.
  StepController(double tolerance, double min_step, double max_step, double first);
  /// The size the next attempt takes [s] (before it is fitted to a stop time), within [min_step, max_step].
  [[nodiscard]] double proposal() const { return proposal_; }
  /// After a converged step of size h with local error estimate `error` [m]: whether it is accepted (error within
  /// the tolerance, or h at min_step: then it is accepted and counted in above_tolerance()). The proposal follows.
  bool judge(double h, double error);
  /// After a step of size h whose Newton iteration failed: the proposal halves (not below min_step).
  void failed(double h);
  /// Whether the last attempt was rejected or failed (the next step is fitted anew).
  [[nodiscard]] bool after_rejection() const { return after_rejection_; }
  [[nodiscard]] long rejected() const { return rejected_; }  ///< steps redone because their error was too large
  /// Steps accepted at min_step with an error estimate above the tolerance.
  [[nodiscard]] long above_tolerance() const { return above_tolerance_; }
  [[nodiscard]] double min_step() const { return min_step_; }
  /// The controller's state, for a checkpoint (restore() takes what state() gave, bit for bit).
  [[nodiscard]] std::vector<double> state() const;
  void restore(const std::vector<double>& state);  ///< throws std::invalid_argument for a malformed one
  static constexpr std::size_t kStateSize = 5;

 private:
  double tolerance_, min_step_, max_step_;
  double proposal_;
  double previous_ratio_ = 1.0;  ///< e_{n−1} / E of the last accepted step (1 before the first)
  bool after_rejection_ = false;  ///< the last attempt was rejected or failed: the next proposal does not grow
  long rejected_ = 0, above_tolerance_ = 0;
};

}  // namespace flexbody::runtime::detail
