// check_options() (generalized_alpha.hpp): the ranges of GeneralizedAlphaOptions, in one place.
#include "flexbody/runtime/generalized_alpha.hpp"

#include <charconv>
#include <cmath>
#include <string>
#include <utility>

namespace flexbody::runtime {
namespace {

// The shortest text that reads back as `value`, as fmt's {} writes it in the scene reader's other messages: fixed
// notation for decimal exponents from -4 to 15 (0.0005, not 5e-04), scientific beyond.
std::string shortest(double value) {
  char text[64];
  auto end = std::to_chars(text, text + sizeof text, value, std::chars_format::scientific).ptr;
  const std::string scientific(text, end);
  const std::size_t e = scientific.find('e');
  const int exponent = e == std::string::npos ? 0 : std::stoi(scientific.substr(e + 1));
  if (!std::isfinite(value) || exponent < -4 || exponent >= 16) return scientific;
  end = std::to_chars(text, text + sizeof text, value, std::chars_format::fixed).ptr;
  return {text, end};
}

// "name must ..., got value".
OptionProblem problem(const char* option, const std::string& rule, double value) {
  return {option, std::string(option) + ' ' + rule + ", got " + shortest(value)};
}

}  // namespace

std::optional<OptionProblem> check_options(const GeneralizedAlphaOptions& o) {
  const bool automatic = o.error_tolerance > 0.0;
  if (!(o.rho_infinity >= 0.0 && o.rho_infinity <= 1.0))
    return problem("rho_inf", "must lie in [0, 1]", o.rho_infinity);
  if (!(o.step > 0.0) || !std::isfinite(o.step))
    return problem("step",
                   automatic ? "must be a positive time in seconds (the first step of error control)"
                             : "must be a positive time in seconds",
                   o.step);
  if (!(o.error_tolerance >= 0.0) || !std::isfinite(o.error_tolerance))
    return problem("error_tolerance", "must be >= 0 [m] (0: fixed steps)", o.error_tolerance);
  if (!(o.max_step >= 0.0)) return problem("max_step", "must be >= 0 [s] (0: no limit)", o.max_step);
  if (o.max_step > 0.0 && o.max_step < o.step) {
    return OptionProblem{"max_step", "max_step " + shortest(o.max_step) + " s is smaller than the " +
                                         (automatic ? "initial " : "") + "step " + shortest(o.step) + " s"};
  }
  if (!(o.min_step >= 0.0) || !std::isfinite(o.min_step))
    return problem("min_step", "must be a positive time in seconds, or 0 for the step / 64", o.min_step);
  if (o.min_step > o.step) {
    return OptionProblem{"min_step", "min_step " + shortest(o.min_step) + " s is larger than the " +
                                         (automatic ? "initial " : "") + "step " + shortest(o.step) +
                                         " s: it is the smallest step " +
                                         (automatic ? "the error control may take" : "a failed step is halved into")};
  }
  if (o.max_iterations < 1) return problem("max_iterations", "must be at least 1", o.max_iterations);
  if (!(o.tolerance > 0.0)) return problem("tolerance", "must be positive", o.tolerance);
  if (o.tolerance > kLargestTolerance) {
    return OptionProblem{"tolerance", "tolerance " + shortest(o.tolerance) + " is above " +
                                          shortest(kLargestTolerance) +
                                          ": it is relative to each step's predictor-corrector distance (the step's "
                                          "local error), and above that the iteration error exceeds it"};
  }
  if (!(o.deformation_limit >= 0.0))
    return problem("deformation_limit", "must be >= 0 (a fraction of the body's size; 0: no check)",
                   o.deformation_limit);
  const std::pair<const char*, double> spin_levels[] = {{"spin_warning", o.spin_warning},
                                                        {"spin_limit", o.spin_limit},
                                                        {"stiffened_spin_warning", o.stiffened_spin_warning},
                                                        {"stiffened_spin_limit", o.stiffened_spin_limit}};
  for (const auto& [option, level] : spin_levels)
    if (!(level >= 0.0))
      return problem(option, "must be >= 0 (a multiple of the lowest elastic frequency; 0: no check)", level);
  return std::nullopt;
}

}  // namespace flexbody::runtime
