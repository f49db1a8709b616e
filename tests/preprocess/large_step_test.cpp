// Steps much longer than a flexible body's periods (issue 47): the sample bracket pendulum (meshes/bracket.yaml, the
// quick start's part) in the improved GCMS at the steps where the FFRF runs, its error against its own h = 1e-4 s run
// compared with the FFRF's against its own.
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace {

// bore_3's path over 0.5 s at step h (rows every 16 ms), or the run's error line.
struct Path {
  std::vector<std::vector<double>> rows;
  std::string error;
  long retried_steps = 0;     ///< fbsim --json's
  double smallest_step = 0.0;
};

Path swing(const std::filesystem::path& dir, const std::string& formulation, int modes, double h) {
  const std::string name = fmt::format("{}-{}-{:g}", formulation, modes, h);
  flexbody::test::write_text(
      dir / (name + ".yaml"),
      fmt::format("bodies:\n  bracket: {{file: bracket.fbh5, modes: {}, formulation: {}}}\n"
                  "joints:\n  pivot: {{type: revolute, body: bracket, interface: bore_1, to: ground, axis: [0, 0, 1]}}\n"
                  "gravity: [0, -9.81, 0]\n"
                  "integrator: {{type: generalized-alpha, rho_inf: 0.9, step: {:.17g}, end: 0.5, output_interval: 0.016}}\n"
                  "outputs:\n  bore_3: {{body: bracket, interface: bore_3, quantities: [position]}}\n",
                  modes, formulation, h));
  const flexbody::test::CliRun run = flexbody::test::run_fbsim(dir, fmt::format("{0}.yaml -o {0}-out --json", name));
  if (run.exit_code != 0) return {{}, run.err};
  const nlohmann::json summary = nlohmann::json::parse(run.out);
  return {flexbody::test::read_csv_numbers(dir / (name + "-out") / "bore_3.csv"), {}, summary["retried_steps"].get<long>(),
          summary["smallest_step_s"].get<double>()};
}

// The largest distance between two paths at their common rows [m].
double largest_distance(const Path& a, const Path& reference) {
  EXPECT_EQ(a.rows.size(), reference.rows.size());
  double worst = 0.0;
  for (std::size_t r = 0; r < std::min(a.rows.size(), reference.rows.size()); ++r) {
    EXPECT_NEAR(a.rows[r][0], reference.rows[r][0], 1e-9);
    worst = std::max(worst, std::hypot(a.rows[r][1] - reference.rows[r][1], a.rows[r][2] - reference.rows[r][2],
                                       a.rows[r][3] - reference.rows[r][3]));
  }
  return worst;
}

}  // namespace

// The bracket (about 4 cm, 2.0-12 kHz) swings at up to 10 rad/s. Its GCMS fields reach 418 kHz, so ω h is in the
// hundreds to thousands at these steps, where before the fields' predictor (field_predictor.hpp) the GCMS diverged
// at 4 ms (t = 0.112 s) and at 8 ms (the first step). The target is the issue's: at most twice the FFRF's error at
// the same step and modes. Measured: 1.64e-4 against 9.2e-5 m at 4 ms, 6.3e-4 against 3.7e-4 at 8 ms (a ratio of
// 1.7-1.8 at every step from 1 ms: the two formulations' own discretisation errors, since A's nine coordinates and
// the Euler parameters are not the same coordinates). At 16 ms two or three steps fail whole (the stabilised form's
// position correction, docs/formulations.md) and are taken in halves: 2.4e-3 against 1.4e-3 m.
TEST(LargeSteps, TheGcmsBracketPendulumRunsWhereTheFfrfDoes) {
  const auto dir = flexbody::test::scratch_dir();
  const flexbody::test::CliRun prep = flexbody::test::run_fbprep(
      dir, fmt::format("'{}/meshes/bracket.yaml' -o bracket.fbh5 --modes 12 -q", FLEXBODY_SOURCE_DIR));
  ASSERT_EQ(prep.exit_code, 0) << prep.err;
  for (const int modes : {6, 12}) {
    const Path gcms_reference = swing(dir, "gcms", modes, 1e-4), ffrf_reference = swing(dir, "ffrf", modes, 1e-4);
    ASSERT_TRUE(gcms_reference.error.empty()) << gcms_reference.error;
    ASSERT_TRUE(ffrf_reference.error.empty()) << ffrf_reference.error;
    for (const double h : {4e-3, 8e-3, 16e-3}) {
      SCOPED_TRACE(fmt::format("{} modes, h = {} s", modes, h));
      const Path gcms = swing(dir, "gcms", modes, h), ffrf = swing(dir, "ffrf", modes, h);
      ASSERT_TRUE(gcms.error.empty()) << gcms.error;
      ASSERT_TRUE(ffrf.error.empty()) << ffrf.error;
      const double gcms_error = largest_distance(gcms, gcms_reference), ffrf_error = largest_distance(ffrf, ffrf_reference);
      EXPECT_GT(ffrf_error, 1e-5);  // the comparison is of discretisation errors, far above the references' own
      EXPECT_LE(gcms_error, 2.0 * ffrf_error) << "GCMS " << gcms_error << " m, FFRF " << ffrf_error << " m";
      EXPECT_EQ(ffrf.retried_steps, 0);
      EXPECT_EQ(gcms.retried_steps > 0, h > 1e-2) << gcms.retried_steps;  // measured: 3 and 2 at 16 ms, none below
      EXPECT_GE(gcms.smallest_step, h / 64 * (1 - 1e-9));  // min_step's default (0.5 s ends on a shortened step)
    }
  }
}
