// The output budget (issue 32): a run whose outputs are estimated over the budget is refused before its first step,
// with one line naming the scene line that sets the largest part, and no output directory; --max-output and the
// scene's output_budget change it; the summary reports what was estimated and what was written.
#include "fbsim_cli_helpers.hpp"

#include "flexbody/scene/output_budget.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

using fbsim_cli::bar_folder;
using fbsim_cli::CliRun;
using fbsim_cli::expect_scene_error;
using fbsim_cli::run_fbsim;
using fbsim_cli::write_text;

namespace {

// The issue's pendulum (1e-4 s steps, 2 s) with `extra` lines.
std::string pendulum(const std::string& integrator_extra, const std::string& extra) {
  std::string scene = fbsim_cli::kIssueScene;
  scene.replace(scene.find("end: 2.0"), 8, "end: 2.0" + integrator_extra);
  return scene + extra;
}

}  // namespace

TEST(OutputBudget, SizesAreReadAndWrittenAsPeopleWriteThem) {
  using flexbody::scene::parse_size;
  EXPECT_EQ(parse_size("10GB"), 10e9);
  EXPECT_EQ(parse_size("500 MB"), 500e6);
  EXPECT_EQ(parse_size("2 KiB"), 2048.0);
  EXPECT_EQ(parse_size("1e9"), 1e9);
  for (const char* bad : {"", "GB", "-1GB", "10 parsecs", "0", "nan"}) EXPECT_THROW(static_cast<void>(parse_size(bad)), std::invalid_argument) << bad;
  EXPECT_EQ(flexbody::scene::format_size(8.8e9), "8.8 GB");
  EXPECT_EQ(flexbody::scene::format_size(900.0), "900 B");
  EXPECT_EQ(flexbody::scene::format_size(1.94e14), "194 TB");
}

TEST(OutputBudget, ParaViewFramesOverTheBudgetAreRefusedBeforeTheFirstStep) {
  // 20 001 frames of the bar (315 kB each) every step: 6.3 GB, over a 100 MB budget; the line is paraview's `every`.
  const std::string scene = pendulum("", "output_budget: {size: 100 MB}\nparaview:\n  every: 1\n");
  expect_scene_error(scene, 11, "paraview body 'bar': 20001 frames (6.3 GB in 20002 files; the step is set at "
                                "bad.yaml:6): the run would write about 6.3 GB in 20003 files, over the output "
                                "budget of 100 MB and 100000 files (write less often, or raise it: fbsim --max-output "
                                "SIZE or the scene's output_budget: {size: SIZE})");
  EXPECT_FALSE(std::filesystem::exists(bar_folder() / "bad_out"));  // no directory, no file
  // The default budget's files: 20 001 frames every step, over 100 000 at 2e-5 s steps.
  std::string many = pendulum("", "paraview: {every: 1}\n");
  many.replace(many.find("step: 1.0e-4"), 12, "step: 1.0e-5");
  expect_scene_error(many, 9, "paraview body 'bar': 200001 frames");
  // Without `every` the paraview key's own line (a block map's value starts on the next line).
  std::string block = pendulum("", "paraview:\n  stresses: false\n");
  block.replace(block.find("step: 1.0e-4"), 12, "step: 1.0e-5");
  expect_scene_error(block + "output_budget: {size: 1 MB}\n", 9, "paraview body 'bar': 101 frames");
}

TEST(OutputBudget, CsvRowsOverTheBudgetNameTheIntegratorsLine) {
  // 20 001 rows of t, x, y, z: about 2 MB, over 1 MB; output_every is not given, so the integrator's line.
  expect_scene_error(pendulum("", "output_budget: {size: 1 MB}\n"), 6, "CSV outputs (1 file): 20001 rows each (2 MB");
  expect_scene_error(pendulum(", output_every: 10", "output_budget: {size: 100 kB}\n"), 6, "CSV outputs (1 file): 2001 rows each");
  expect_scene_error(pendulum("", "output_budget: {size: 1 GB, files: 0}\n"), 9, "output_budget files must be a whole number");
  expect_scene_error(pendulum("", "output_budget: {size: 1 parsec}\n"), 9, "output_budget size: '1 parsec' is not a size");
}

TEST(OutputBudget, MaxOutputChangesItAndTheSummaryReportsWhatWasWritten) {
  const auto& dir = bar_folder();
  write_text(dir / "budget.yaml", pendulum("", "monitors: true\nparaview: {every: 100}\n"));
  const CliRun refused = run_fbsim(dir, "budget.yaml -o budget_out --end 0.02 --max-output 10kB -q");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("over the output budget of 10 kB"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "budget_out"));
  const CliRun bad = run_fbsim(dir, "budget.yaml -o budget_out --max-output 10parsec -q");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("fbsim: error: --max-output: '10parsec' is not a size"), std::string::npos) << bad.err;

  const CliRun run = run_fbsim(dir, "budget.yaml -o budget_out --end 0.02 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  double bytes = 0.0, files = 0.0;  // what is on disk
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir / "budget_out"))
    if (entry.is_regular_file()) {
      bytes += static_cast<double>(entry.file_size());
      files += 1.0;
    }
  EXPECT_EQ(json["output_bytes"].get<double>(), bytes);
  EXPECT_EQ(json["output_files"].get<double>(), files);  // tip.csv, monitors.csv, bar.pvd and 3 frames
  EXPECT_EQ(files, 6.0);
  // The estimate: the frames' arrays exactly, the XML and the CSV values' lengths roughly (measured 1.04 of it).
  EXPECT_NEAR(json["estimated_output_bytes"].get<double>(), bytes, 0.15 * bytes);
}

TEST(OutputInterval, RowsAndFramesFallAtTheSameTimesWhateverTheStep) {
  // Issue 32: outputs by time, so that a smaller step does not multiply them.
  const auto& dir = bar_folder();
  for (const std::string step : {"1.0e-4", "2.0e-4", "3.0e-4"}) {
    SCOPED_TRACE(step);
    std::string scene = pendulum(", output_interval: 0.005", "paraview: {interval: 0.01, stresses: false}\n");
    scene.replace(scene.find("step: 1.0e-4"), 12, "step: " + step);
    write_text(dir / "interval.yaml", scene);
    const CliRun run = run_fbsim(dir, "interval.yaml -o interval_out --end 0.02 -q");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const std::vector<double> times = fbsim_cli::times_of(dir / "interval_out" / "tip.csv");
    ASSERT_EQ(times.size(), 5u);  // t = 0, the first step at or after 0.005, 0.010, 0.015, and the end 0.02
    const double h = std::stod(step);
    for (std::size_t k = 0; k < times.size(); ++k) {
      EXPECT_GE(times[k], 0.005 * static_cast<double>(k) - 1e-12);
      EXPECT_LT(times[k], 0.005 * static_cast<double>(k) + h);  // within a step after its multiple
    }
    EXPECT_EQ(times.back(), 0.02);
    std::size_t frames = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir / "interval_out" / "bar")) frames += entry.is_regular_file();
    EXPECT_EQ(frames, 3u);  // t = 0, 0.01, 0.02
    std::filesystem::remove_all(dir / "interval_out");
  }
  expect_scene_error(pendulum(", output_every: 10, output_interval: 0.005", ""), 6,
                     "integrator: output_every (steps) and output_interval (seconds) are both given; give one");
  expect_scene_error(pendulum("", "paraview: {every: 10, interval: 0.01}\n"), 9,
                     "paraview: every (steps) and interval (seconds) are both given; give one");
  // The budget counts by time too: 2 s at a row every 2e-4 s, whatever the step; at most a row per step.
  expect_scene_error(pendulum(", output_interval: 2.0e-4", "output_budget: {size: 500 kB}\n"), 6,
                     "CSV outputs (1 file): 10001 rows each");
  expect_scene_error(pendulum(", output_interval: 1.0e-6", "output_budget: {size: 1 MB}\n"), 6,
                     "CSV outputs (1 file): 20001 rows each");
}
