#include "step_controller.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace flexbody::runtime::detail {
namespace {

constexpr double kSafety = 0.9;                  // aim at 0.9³ ≈ 0.73 of the tolerance
constexpr double kIntegral = 0.7 / 3.0, kProportional = 0.4 / 3.0;  // Hairer & Wanner II, Eq. (2.43c), order 2 (k = 3)
constexpr double kLeastFactor = 0.2, kMostFactor = 2.0;

}  // namespace

StepController::StepController(double tolerance, double min_step, double max_step, double first)
    : tolerance_(tolerance), min_step_(min_step), max_step_(max_step), proposal_(first) {
  if (!(tolerance > 0.0) || !(min_step > 0.0) || !(min_step <= first) || !(first <= max_step))
    throw std::invalid_argument("step controller: 0 < min_step <= first step <= max_step and a positive "
                                "tolerance are required");
}

bool StepController::judge(double h, double error) {
  const double ratio = error / tolerance_;  // e / E; NaN fails both tests below and is rejected
  const bool at_floor = h <= min_step_ * (1.0 + 1e-9);
  if (!(ratio <= 1.0) && !at_floor) {
    ++rejected_;
    const double factor = std::isfinite(ratio) ? std::max(kLeastFactor, kSafety * std::cbrt(1.0 / ratio)) : kLeastFactor;
    proposal_ = std::max(min_step_, std::min(h * std::min(factor, 1.0), max_step_));
    after_rejection_ = true;
    return false;
  }
  if (!(ratio <= 1.0)) ++above_tolerance_;
  // A step shortened to land on a stop time says little about the proposal when it is much shorter (its error may be
  // round-off); otherwise its error is scaled to the proposal's size, e ∝ h³, and the proposal is judged by it.
  if (h < 0.5 * proposal_) {
    after_rejection_ = false;
    return true;
  }
  const double e = std::max(ratio * std::pow(proposal_ / h, 3.0), 1e-10);  // a free flight's 0 grows the most
  double factor = kSafety * std::pow(e, -kIntegral) * std::pow(previous_ratio_, kProportional);
  factor = std::clamp(factor, kLeastFactor, after_rejection_ ? 1.0 : kMostFactor);
  proposal_ = std::clamp(proposal_ * factor, min_step_, max_step_);
  previous_ratio_ = e;
  after_rejection_ = false;
  return true;
}

void StepController::failed(double h) {
  proposal_ = std::max(min_step_, 0.5 * h);
  after_rejection_ = true;
}

std::vector<double> StepController::state() const {
  return {proposal_, previous_ratio_, after_rejection_ ? 1.0 : 0.0, static_cast<double>(rejected_),
          static_cast<double>(above_tolerance_)};
}

void StepController::restore(const std::vector<double>& s) {
  if (s.size() != kStateSize || !(s[0] >= min_step_ && s[0] <= max_step_) || !(s[1] > 0.0) || !(s[3] >= 0.0) ||
      !(s[4] >= 0.0))
    throw std::invalid_argument("checkpoint: integrator.control is malformed or outside this run's step limits");
  proposal_ = s[0];
  previous_ratio_ = s[1];
  after_rejection_ = s[2] != 0.0;
  rejected_ = static_cast<long>(s[3]);
  above_tolerance_ = static_cast<long>(s[4]);
}

}  // namespace flexbody::runtime::detail
