// fbsim's checkpoints from the command line (issue 32): SIGTERM mid-run stops after the step in progress with one
// line, leaving DIR/checkpoint.h5, and ends fbsim by the signal (exit status 143); `fbsim SCENE --resume DIR` continues and its outputs are the
// uninterrupted run's, byte for byte; the scene's checkpoint: {interval} writes checkpoints as it runs and at the end,
// from which --resume --end runs on; refusals are one line with exit code 2.
#include "bounded_run.hpp"
#include "fbsim_cli_helpers.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

using namespace fbsim_cli;

namespace {

std::string bytes_of(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The issue's pendulum (the 8-mode bar) for `end` seconds, rows every 100 steps, monitors.
std::string pendulum(double end, const std::string& extra = "") {
  std::string scene = kIssueScene;
  scene.replace(scene.find("end: 2.0"), 8, "end: " + std::to_string(end) + ", output_every: 100");
  return scene + "monitors: true\n" + extra;
}

void expect_same_files(const std::filesystem::path& a, const std::filesystem::path& b) {
  for (const char* name : {"tip.csv", "monitors.csv"}) {
    const std::string first = bytes_of(a / name), second = bytes_of(b / name);
    EXPECT_GT(first.size(), 100u) << name;
    EXPECT_TRUE(first == second) << name << " differs: " << first.size() << " against " << second.size() << " bytes";
  }
}

}  // namespace

TEST(FbsimCheckpoint, SigtermLeavesACheckpointThatResumesBitForBit) {
  const auto& dir = bar_folder();
  // 60000 steps (about a second on the 2-core machine), the signal once tip.csv has bytes on disk: its stream's
  // first flush, about 10000 steps into the run, after fbsim set its handlers up (before the first step).
  write_text(dir / "long.yaml", pendulum(6.0));
  std::filesystem::remove_all(dir / "long_whole");
  std::filesystem::remove_all(dir / "long_part");
  ASSERT_EQ(run_fbsim(dir, "long.yaml -o long_whole -q").exit_code, 0);
  const std::string fbsim = FLEXBODY_FBSIM;
  const auto scene = (dir / "long.yaml").string(), part = (dir / "long_part").string();
  const std::filesystem::path rows = dir / "long_part" / "tip.csv";
  const flexbody::test::BoundedRun stopped =
      flexbody::test::run_bounded(fbsim, {scene, "-o", part, "-q"}, dir / "long_stopped", std::chrono::seconds(120), [&] {
        std::error_code missing;
        const auto size = std::filesystem::file_size(rows, missing);
        return !missing && size > 0;
      });
  ASSERT_FALSE(stopped.timed_out);
  EXPECT_EQ(stopped.signal, SIGTERM) << "ended by the signal, as a shell expects (exit status 143); " << stopped.err;
  EXPECT_NE(stopped.err.find("fbsim: stopped by SIGTERM at t = "), std::string::npos) << stopped.err;
  EXPECT_NE(stopped.err.find("continue with fbsim " + scene + " --resume " + part), std::string::npos) << stopped.err;
  EXPECT_EQ(std::count(stopped.err.begin(), stopped.err.end(), '\n'), 1) << stopped.err;
  ASSERT_TRUE(std::filesystem::exists(dir / "long_part" / "checkpoint.h5"));
  const CliRun resumed = run_fbsim(dir, "long.yaml --resume long_part --json");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("\"resumed_at_s\":"), std::string::npos);
  EXPECT_NE(resumed.out.find("\"steps\":60000"), std::string::npos) << resumed.out;  // the whole run's count
  expect_same_files(dir / "long_whole", dir / "long_part");
  EXPECT_FALSE(std::filesystem::exists(dir / "long_part" / "checkpoint.h5"));  // done: it no longer matches the files
}

TEST(FbsimCheckpoint, TheIntervalWritesCheckpointsAndResumeRunsOnToALaterEnd) {
  const auto& dir = bar_folder();
  write_text(dir / "interval.yaml", pendulum(0.05, "checkpoint: {interval: 0.01}\n"));
  std::filesystem::remove_all(dir / "interval_out");
  std::filesystem::remove_all(dir / "interval_whole");
  // Checkpoints every 10 ms of wall-clock time, and the last at the end.
  const CliRun first = run_fbsim(dir, "interval.yaml -o interval_out");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  EXPECT_NE(first.out.find("checkpoint interval_out/checkpoint.h5 at t = 0.05 s"), std::string::npos) << first.out;
  std::string before_end = bytes_of(dir / "interval_out" / "tip.csv");
  before_end.erase(before_end.rfind('\n', before_end.size() - 2) + 1);  // the rows before the last step's
  // From there to 0.1 s, against a run to 0.1 s from the start. The first run's last step ended on 0.05 s exactly
  // (step_to: h = 0.05 − t₄₉₉ differs from 1e-4 s in its last bits), the longer run's was a step of h: the runs
  // agree to round-off after it (measured 7.8e-16 m at 0.1 s), bit for bit before it.
  const CliRun longer = run_fbsim(dir, "interval.yaml --resume interval_out --end 0.1");
  ASSERT_EQ(longer.exit_code, 0) << longer.err;
  EXPECT_NE(longer.out.find("resumed at t = 0.05 s"), std::string::npos) << longer.out;
  ASSERT_EQ(run_fbsim(dir, "interval.yaml -o interval_whole -q --end 0.1").exit_code, 0);
  EXPECT_EQ(bytes_of(dir / "interval_whole" / "tip.csv").substr(0, before_end.size()), before_end);
  const auto whole = csv_numbers(dir / "interval_whole" / "tip.csv"), resumed = csv_numbers(dir / "interval_out" / "tip.csv");
  ASSERT_EQ(whole.size(), 11u);  // 0, 0.01, ..., 0.1 s
  ASSERT_EQ(resumed.size(), whole.size());
  for (std::size_t r = 0; r < whole.size(); ++r)
    for (std::size_t c = 0; c < whole[r].size(); ++c) EXPECT_NEAR(resumed[r][c], whole[r][c], 1e-14) << r << ", " << c;
}

TEST(FbsimCheckpoint, ACheckpointThatCannotBeWrittenIsAWarning) {
  // DIR/checkpoint.h5 is a directory (with a file in it): every write fails at its rename. The run goes on.
  const auto& dir = bar_folder();
  write_text(dir / "blocked.yaml", pendulum(0.02, "checkpoint: {interval: 1.0e-6}\n"));
  std::filesystem::remove_all(dir / "blocked_out");
  std::filesystem::create_directories(dir / "blocked_out" / "checkpoint.h5");
  write_text(dir / "blocked_out" / "checkpoint.h5" / "keep", "x");
  const CliRun run = run_fbsim(dir, "blocked.yaml -o blocked_out -q");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("fbsim: warning: t = 0.0001 s: the checkpoint could not be written"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("fbsim: warning: the checkpoint at the end could not be written"), std::string::npos) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 2) << run.err;  // once per run, and the end
  EXPECT_EQ(csv_numbers(dir / "blocked_out" / "tip.csv").size(), 3u);  // t = 0, 0.01, 0.02: the run went on
}

TEST(FbsimCheckpoint, RefusalsAreOneLine) {
  const auto& dir = bar_folder();
  write_text(dir / "refused.yaml", pendulum(0.01, "checkpoint: {interval: 1.0e-6}\n"));
  std::filesystem::remove_all(dir / "refused_out");
  ASSERT_EQ(run_fbsim(dir, "refused.yaml -o refused_out -q").exit_code, 0);
  auto refused = [&](const std::string& arguments, const std::string& message) {
    const CliRun run = run_fbsim(dir, arguments);
    EXPECT_EQ(run.exit_code, 2) << arguments;
    EXPECT_NE(run.err.find(message), std::string::npos) << arguments << ": " << run.err;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  };
  refused("refused.yaml --resume nowhere", "--resume nowhere: no checkpoint.h5 there");
  refused("refused.yaml --resume refused_out -o elsewhere", "a run resumes in its own output directory");
  write_text(dir / "refused_other.yaml", pendulum(0.01, "checkpoint: {interval: 2.0e-6}\n"));
  refused("refused_other.yaml --resume refused_out", "refused_out/checkpoint.h5: written for another scene");
  std::filesystem::copy_file(dir / "bar.fbh5", dir / "refused_out" / "checkpoint.h5",
                             std::filesystem::copy_options::overwrite_existing);
  refused("refused.yaml --resume refused_out", "refused_out/checkpoint.h5: is a body file, not a checkpoint");
  write_text(dir / "refused_bad.yaml", pendulum(0.01, "checkpoint: {interval: -1}\n"));
  refused("refused_bad.yaml -o refused_bad", "refused_bad.yaml:10:");
}
