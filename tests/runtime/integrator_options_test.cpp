// check_options (generalized_alpha.hpp): each option out of its range is named with its value, the defaults pass,
// and GeneralizedAlpha's constructor refuses with the same words.
#include "rigid_pendulum_helpers.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <optional>
#include <string>

namespace {

using namespace rigid_pendulum;

// The option check_options names for `options`, and its message; "" for none.
std::pair<std::string, std::string> named(const fr::GeneralizedAlphaOptions& options) {
  const std::optional<fr::OptionProblem> problem = fr::check_options(options);
  return problem ? std::pair{problem->option, problem->message} : std::pair{std::string(), std::string()};
}

TEST(IntegratorOptions, TheDefaultsPass) { EXPECT_EQ(named(fr::GeneralizedAlphaOptions{}).first, ""); }

TEST(IntegratorOptions, EachOptionOutOfRangeIsNamedWithItsValue) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto with = [](auto set) {
    fr::GeneralizedAlphaOptions o;
    set(o);
    return named(o);
  };
  EXPECT_EQ(with([](auto& o) { o.rho_infinity = 1.5; }),
            std::pair(std::string("rho_inf"), std::string("rho_inf must lie in [0, 1], got 1.5")));
  EXPECT_EQ(with([&](auto& o) { o.rho_infinity = nan; }).first, "rho_inf");
  EXPECT_EQ(with([](auto& o) { o.step = 0.0; }).second, "step must be a positive time in seconds, got 0");
  EXPECT_EQ(with([](auto& o) { o.step = std::numeric_limits<double>::infinity(); }).first, "step");
  EXPECT_EQ(with([](auto& o) { o.error_tolerance = -1e-6; }).second,
            "error_tolerance must be >= 0 [m] (0: fixed steps), got -1e-06");
  EXPECT_EQ(with([](auto& o) { o.max_step = 0.5e-3; }).second, "max_step 0.0005 s is smaller than the step 0.001 s");
  EXPECT_EQ(with([](auto& o) { o.min_step = 2e-3; }).second,
            "min_step 0.002 s is larger than the step 0.001 s: it is the smallest step a failed step is halved into");
  EXPECT_EQ(with([](auto& o) {
              o.error_tolerance = 1e-6;
              o.min_step = 2e-3;
            }).second,
            "min_step 0.002 s is larger than the initial step 0.001 s: it is the smallest step the error control may "
            "take");
  EXPECT_EQ(with([](auto& o) { o.min_step = -1.0; }).first, "min_step");
  EXPECT_EQ(with([](auto& o) { o.max_iterations = 0; }).second, "max_iterations must be at least 1, got 0");
  EXPECT_EQ(with([](auto& o) { o.tolerance = 0.0; }).first, "tolerance");
  EXPECT_EQ(with([](auto& o) { o.tolerance = 1e-2; }).second.substr(0, 28), "tolerance 0.01 is above 0.00");
  EXPECT_EQ(with([](auto& o) { o.deformation_limit = -0.1; }).second,
            "deformation_limit must be >= 0 (a fraction of the body's size; 0: no check), got -0.1");
  EXPECT_EQ(with([](auto& o) { o.spin_warning = -1.0; }).first, "spin_warning");
  EXPECT_EQ(with([&](auto& o) { o.spin_limit = nan; }).first, "spin_limit");
  EXPECT_EQ(with([](auto& o) { o.stiffened_spin_warning = -1.0; }).first, "stiffened_spin_warning");
  EXPECT_EQ(with([](auto& o) { o.stiffened_spin_limit = -1.0; }).first, "stiffened_spin_limit");
}

TEST(IntegratorOptions, TheConstructorRefusesInTheSameWords) {
  fr::BodyModel model = rigid_bar();
  fr::System system;
  system.add_body("bar", model, fr::BodyState{});
  fr::GeneralizedAlphaOptions options;
  options.rho_infinity = -0.5;
  try {
    fr::GeneralizedAlpha integrator(system, options);
    FAIL() << "accepted rho_inf -0.5";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "generalized-alpha: rho_inf must lie in [0, 1], got -0.5");
  }
}

}  // namespace
