// fbsim's run: the end time (the scene's, or --end), the output directory, formulations (FFRF, full order) against
// the GCMS body on the same scene.
#include "cli_run.hpp"
#include "fbsim_cli_helpers.hpp"
#include "flexbody/format/body_file.hpp"
#include "flexbody/runtime/body_model.hpp"
#include "flexbody/runtime/paraview_series.hpp"
#include "test_meshes.hpp"
#include "vtu_read.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include <unistd.h>

using namespace fbsim_cli;


// Issue 13: an end time that is not a whole number of steps was rounded to one (step 3e-4, end 1e-3 ended at 9e-4).
// The last step is now shortened so that the run ends on the end time; the other rows stay at multiples of the
// output interval.
TEST(FbsimCli, TheRunEndsOnTheEndTime) {
  const auto& dir = bar_folder();
  const std::string bodies = R"(bodies:
  bar: {file: bar.fbh5, modes: 8}
joints:
  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}
gravity: [0, -9.81, 0]
outputs:
  tip: {body: bar, interface: tip, quantities: [position]}
)";
  write_text(dir / "short_last.yaml", bodies + "integrator: {step: 3.0e-4, end: 1.0e-3}\n");
  const CliRun run = run_fbsim(dir, "short_last.yaml -o short_last_out --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(nlohmann::json::parse(run.out)["steps"], 4);  // 3 of 3e-4 s and one of 1e-4 s
  const std::vector<double> t = times_of(dir / "short_last_out" / "tip.csv");
  ASSERT_EQ(t.size(), 5u);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(t[k], 3.0e-4 * k, 1e-18) << k;
  EXPECT_EQ(t[4], 1.0e-3);  // exactly the end time

  // Rows every 5 steps, and the end time; the shortened step does not disturb the motion: the tip's path agrees
  // with a run whose step divides the end time, to the time discretisation error.
  write_text(dir / "every.yaml", bodies + "integrator: {step: 1.0e-4, end: 1.05e-3, output_every: 5}\n");
  const CliRun every = run_fbsim(dir, "every.yaml -o every_out -q");
  ASSERT_EQ(every.exit_code, 0) << every.err;
  const std::vector<double> rows = times_of(dir / "every_out" / "tip.csv");
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_NEAR(rows[1], 5e-4, 1e-18);
  EXPECT_NEAR(rows[2], 1e-3, 1e-18);
  EXPECT_EQ(rows[3], 1.05e-3);
  write_text(dir / "even.yaml", bodies + "integrator: {step: 5.0e-5, end: 1.05e-3}\n");
  ASSERT_EQ(run_fbsim(dir, "even.yaml -o even_out -q").exit_code, 0);
  auto last_y = [](const std::filesystem::path& csv) {
    std::ifstream in(csv);
    std::string line, last;
    while (std::getline(in, line)) last = line;
    double time, x, y;
    char c;
    std::istringstream(last) >> time >> c >> x >> c >> y;
    return y;
  };
  // The tip has fallen about 5e-6 m (a rigid bar's would be 8e-6 m: the bending wave from the pivot is still on its
  // way); the two runs agree to 0.1 % of that (measured: 5.6e-9 m, O(h²) errors), 1 % asserted.
  const double fallen = last_y(dir / "even_out" / "tip.csv") - 0.025;
  EXPECT_LT(fallen, -2e-6);
  EXPECT_NEAR(last_y(dir / "every_out" / "tip.csv"), last_y(dir / "even_out" / "tip.csv"), 1e-2 * std::abs(fallen));
}

// fbsim --end T replaces the scene's integrator end (a short trial run of a long scene; the examples' tests): the
// issue's 2 s scene at 1e-4 s ends after 20 steps with --end 2e-3, its rows end on 2e-3 s exactly, and what the
// scene's own end would refuse is refused for --end too, in one line naming the option.
TEST(FbsimCli, EndOnTheCommandLineReplacesTheScenes) {
  const auto& dir = bar_folder();
  write_text(dir / "long.yaml", kIssueScene);
  const CliRun run = run_fbsim(dir, "long.yaml -o long_out --json --end 2e-3");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(nlohmann::json::parse(run.out)["steps"], 20);
  const std::vector<double> t = times_of(dir / "long_out" / "tip.csv");
  ASSERT_FALSE(t.empty());
  EXPECT_EQ(t.back(), 2e-3);
  for (const auto& [end, message] : {std::pair<std::string, std::string>{"0", "--end must be a positive time in seconds, got 0"},
                                     {"1e-5", "--end 1e-05 s is shorter than the scene's integrator step 0.0001 s"},
                                     {"1e6", "would take 1e+10 steps to the end time 1000000 s (--end); at most 1e+09"}}) {
    SCOPED_TRACE(end);
    const CliRun bad = run_fbsim(dir, "long.yaml -o bad_end -q --end " + end);
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find(message), std::string::npos) << bad.err;
    EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad_end"));
  }
}

// How a run ended is in its summary, for a run that reached its end and one whose step failed (here the linear
// model's deformation limit, set far below the bar's sag under gravity so that the first step trips it): fbsim
// prints the summary up to the failure on stdout, its one error line on stderr, and exits 1.
TEST(FbsimCli, TheSummarySaysHowTheRunEnded) {
  const auto& dir = bar_folder();
  write_text(dir / "ends.yaml", kIssueScene);
  const CliRun done = run_fbsim(dir, "ends.yaml -o ends_out --json --end 1e-3");
  ASSERT_EQ(done.exit_code, 0) << done.err;
  const auto reached = nlohmann::json::parse(done.out);
  EXPECT_EQ(reached["termination"], "end reached");
  EXPECT_EQ(reached["termination_message"], "");
  EXPECT_EQ(reached["time_s"], 1e-3);

  std::string scene = kIssueScene;
  scene.replace(scene.find("end: 2.0}"), 9, "end: 2.0, deformation_limit: 1.0e-12}");
  write_text(dir / "fails.yaml", scene);
  const CliRun failed = run_fbsim(dir, "fails.yaml -o fails_out --json");
  EXPECT_EQ(failed.exit_code, 1) << failed.err;
  EXPECT_EQ(std::count(failed.err.begin(), failed.err.end(), '\n'), 1) << failed.err;
  EXPECT_NE(failed.err.find("left the small-deformation range"), std::string::npos) << failed.err;
  const auto summary = nlohmann::json::parse(failed.out);
  EXPECT_EQ(summary["termination"], "step failed");
  EXPECT_NE(summary["termination_message"].get<std::string>().find("left the small-deformation range"),
            std::string::npos);
  EXPECT_EQ(summary["time_s"], 0.0);  // the last completed step: the start
  EXPECT_EQ(summary["steps"], 0);
  const CliRun text = run_fbsim(dir, "fails.yaml -o fails_text");
  EXPECT_EQ(text.exit_code, 1) << text.err;
  EXPECT_NE(text.out.find("ended at t = 0 s: step failed (t = 0.0001 s: body 'bar' left the small-deformation range"),
            std::string::npos)
      << text.out;
}

// Issue 13: an output directory that is an existing file gave "filesystem error: ..." (exit code 1).
TEST(FbsimCli, AnOutputDirectoryThatIsAFileIsRefused) {
  const auto& dir = bar_folder();
  std::string scene = kIssueScene;
  scene.replace(scene.find("end: 2.0"), 8, "end: 0.001");
  write_text(dir / "filed.yaml", scene);
  write_text(dir / "a_file", "keep me\n");
  const CliRun given = run_fbsim(dir, "filed.yaml -o a_file -q");
  EXPECT_EQ(given.exit_code, 2);
  EXPECT_EQ(given.err, "fbsim: error: -o a_file: is an existing file, not a directory; choose another output "
                       "directory with -o\n");
  write_text(dir / "filed_results", "keep me too\n");
  const CliRun by_default = run_fbsim(dir, "filed.yaml -q");
  EXPECT_EQ(by_default.exit_code, 2);
  EXPECT_EQ(by_default.err, "fbsim: error: filed_results (the default output directory: the scene's name + _results): "
                            "is an existing file, not a directory; choose another output directory with -o\n");
  EXPECT_EQ(flexbody::test::slurp(dir / "a_file"), "keep me\n");
  EXPECT_EQ(flexbody::test::slurp(dir / "filed_results"), "keep me too\n");
  // A directory that cannot be made (its parent is a file) is one line too, naming it.
  const CliRun below = run_fbsim(dir, "filed.yaml -o a_file/sub -q");
  EXPECT_EQ(below.exit_code, 1);
  EXPECT_EQ(std::count(below.err.begin(), below.err.end(), '\n'), 1) << below.err;
  EXPECT_NE(below.err.find("a_file/sub: cannot create the output directory: Not a directory"), std::string::npos)
      << below.err;
}

// Issue 13: a scene the user cannot read said "cannot open the scene" without why.
TEST(FbsimCli, AnUnreadableSceneSaysWhy) {
  if (::geteuid() == 0) GTEST_SKIP() << "runs as root, which reads a file of mode 000 anyway";
  const auto& dir = bar_folder();
  write_text(dir / "locked.yaml", kIssueScene);
  std::filesystem::permissions(dir / "locked.yaml", std::filesystem::perms::none);
  const CliRun run = run_fbsim(dir, "locked.yaml -o locked_out -q");
  std::filesystem::permissions(dir / "locked.yaml", std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_EQ(run.err, "fbsim: error: locked.yaml: cannot open the scene: Permission denied\n");
}

TEST(FbsimCli, AFloatingFrameBodyRunsTheSameSceneAsTheGcmsBody) {
  // Issue 14: `formulation: ffrf` moves the same body file's modes in floating-frame coordinates, in the mean-axis
  // frame (the GCMS's) or attached to an interface. The issue's pendulum for 0.05 s: every output works for it, and
  // the tip path follows the GCMS body's to well within what the elasticity adds to the rigid swing.
  const auto& dir = bar_folder();
  auto scene = [](const std::string& body) {
    return "bodies:\n  bar: {file: bar.fbh5, modes: 4" + body + R"(}
joints:
  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}
gravity: [0, -9.81, 0]
integrator: {step: 1.0e-4, end: 0.05}
outputs:
  tip: {body: bar, interface: tip, quantities: [position, velocity, orientation]}
  modes: {body: bar, quantities: [modal_coordinates]}
  whole: {body: bar, region: body, quantities: [displacement, stress]}
  pin: {joint: pivot, quantities: [reaction_force, reaction_moment]}
paraview: {every: 100}
monitors: true
)";
  };
  std::map<std::string, std::vector<std::vector<double>>> tips, pins;
  for (const auto& [name, body] : std::vector<std::pair<std::string, std::string>>{
           {"gcms", ""}, {"ffrf", ", formulation: ffrf"}, {"root", ", formulation: ffrf, frame: {interface: root}"}}) {
    SCOPED_TRACE(name);
    write_text(dir / (name + ".yaml"), scene(body));
    const CliRun run = run_fbsim(dir, name + ".yaml -o " + name + "_out --json");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto json = nlohmann::json::parse(run.out);
    EXPECT_LT(json["max_constraint_residual"].get<double>(), 1e-9);
    tips[name] = csv_numbers(dir / (name + "_out") / "tip.csv");
    pins[name] = csv_numbers(dir / (name + "_out") / "pin.csv");
    ASSERT_EQ(tips[name].size(), 501u);
    for (const auto& row : csv_numbers(dir / (name + "_out") / "whole.csv"))
      for (double value : row) ASSERT_TRUE(std::isfinite(value));
    const auto modes = csv_numbers(dir / (name + "_out") / "modes.csv");
    EXPECT_EQ(modes.front().size(), 5u);  // t and 4 modal coordinates
    EXPECT_TRUE(std::filesystem::exists(dir / (name + "_out") / "bar.pvd"));
  }
  // The rigid swing moves the tip by ~1.8 cm; the formulations differ by the second-order effects of the
  // deformation (and of the frame). The pin's force rings at the modes the release excites, and those differ: with 4
  // modes the GCMS's basis holds 12 fields (36 coordinates) against FFRF's 4 modal coordinates, so the bar's response
  // to the sudden release differs in its high frequencies (16.0 N against 10.0 N at t = 0). Averaged over the run it
  // is m g / 4 for both (a rigid bar: 48.1 N): the means agree to 1e-4.
  auto mean_force = [](const std::vector<std::vector<double>>& rows) {
    double sum = 0.0;
    for (const auto& row : rows) sum += row[2];
    return sum / static_cast<double>(rows.size());
  };
  for (const std::string name : {"ffrf", "root"}) {
    double largest = 0.0;
    for (std::size_t k = 0; k < tips[name].size(); ++k)
      for (int c = 1; c <= 3; ++c) largest = std::max(largest, std::abs(tips[name][k][c] - tips["gcms"][k][c]));
    EXPECT_LT(largest, 1e-6) << name;  // measured 5.1e-8 m for both frames (they differ by 2.3e-10 m)
    EXPECT_NEAR(mean_force(pins[name]), mean_force(pins["gcms"]), 1e-3 * mean_force(pins["gcms"])) << name;
    EXPECT_NEAR(mean_force(pins[name]), 19.625 * 9.81 / 4, 0.02 * 48.1) << name;
  }
}

TEST(FbsimCli, BadFormulationsNameTheLine) {
  const std::string tail = "integrator: {step: 1.0e-3, end: 0.01}\n";
  expect_scene_error("bodies:\n  bar: {file: bar.fbh5, formulation: acf}\n" + tail, 2,
                     "body 'bar' formulation 'acf' is unknown; use gcms");
  expect_scene_error("bodies:\n  bar: {file: bar.fbh5, frame: mean-axis}\n" + tail, 2,
                     "body 'bar': frame belongs to formulation ffrf");
  // A rigid body moves in the floating frame's coordinates by default, but its frame is the scene's only with
  // formulation: ffrf written out.
  expect_scene_error("bodies:\n  bar: {file: bar.fbh5, modes: rigid, frame: {interface: root}}\n" + tail, 2,
                     "body 'bar': frame belongs to formulation ffrf");
  expect_scene_error("bodies:\n  bar: {file: bar.fbh5, formulation: ffrf, frame: {interface: hub}}\n" + tail, 2,
                     "body 'bar' frame: bar.fbh5: no interface 'hub' to attach the floating frame to (interfaces: root, tip)");
  expect_scene_error("bodies:\n  bar: {file: bar.fbh5, formulation: ffrf, frame: tisserand}\n" + tail, 2,
                     "body 'bar' frame 'tisserand' is unknown; use mean-axis or {interface: NAME}");
}

TEST(FbsimCli, AFullOrderBodyIsTheReferenceTheReducedBodiesApproach) {
  // Issue 14: `modes: full` runs the unreduced improved ACF of the body file's mesh from a scene, so that a scene is its
  // own reference. The issue's pendulum for 0.05 s (its release excites the bar's bending): the tip paths of 2 and 8
  // modes against the full-order body's (free-free modes, rbe3 root). Measured: 4.7e-6 and 1.1e-6 m of a 1.8 cm swing.
  const auto& dir = bar_folder();
  auto scene = [](const std::string& modes) {
    return "bodies:\n  bar: {file: bar.fbh5, modes: " + modes + R"(}
joints:
  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}
gravity: [0, -9.81, 0]
integrator: {step: 1.0e-4, end: 0.05}
outputs:
  tip: {body: bar, interface: tip, quantities: [position]}
  corner: {body: bar, node: 0, quantities: [position, velocity]}
paraview: {every: 250}
monitors: true
)";
  };
  std::map<std::string, std::vector<std::vector<double>>> tips;
  for (const std::string modes : {"full", "2", "8"}) {
    SCOPED_TRACE(modes);
    write_text(dir / ("m" + modes + ".yaml"), scene(modes));
    const CliRun run = run_fbsim(dir, "m" + modes + ".yaml -o m" + modes + "_out --json");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_LT(nlohmann::json::parse(run.out)["max_constraint_residual"].get<double>(), 1e-9);
    tips[modes] = csv_numbers(dir / ("m" + modes + "_out") / "tip.csv");
    ASSERT_EQ(tips[modes].size(), 501u);
    EXPECT_TRUE(std::filesystem::exists(dir / ("m" + modes + "_out") / "bar.pvd"));
  }
  auto error = [&](const std::string& modes) {
    double largest = 0.0;
    for (std::size_t k = 0; k < tips["full"].size(); ++k)
      for (int c = 1; c <= 3; ++c) largest = std::max(largest, std::abs(tips[modes][k][c] - tips["full"][k][c]));
    return largest;
  };
  double travel = 0.0;
  for (const auto& row : tips["full"]) travel = std::max(travel, std::hypot(row[1] - tips["full"][0][1], row[2] - tips["full"][0][2]));
  ASSERT_GT(travel, 0.01);
  EXPECT_LT(error("8"), 0.5 * error("2"));  // the reduction error falls with the modes (measured 0.23 of it)
  EXPECT_LT(error("8"), 3e-6);
}

TEST(FbsimCli, WhatAFullOrderBodyCannotDoIsRefusedByLine) {
  const std::string head = "bodies:\n  bar: {file: bar.fbh5, modes: full";
  const std::string tail = "integrator: {step: 1.0e-3, end: 0.01}\n";
  expect_scene_error(head + ", formulation: ffrf}\n" + tail, 2,
                     "body 'bar': formulation ffrf moves modes in a floating frame; modes: full is the unreduced");
  expect_scene_error(head + ", damping: {modal: 0.01}}\n" + tail, 2,
                     "body 'bar' damping: modes: full takes stiffness-proportional damping only");
  expect_scene_error(head + ", damping: {rayleigh: {alpha: 1, beta: 1e-5}}}\n" + tail, 2,
                     "body 'bar' damping: modes: full takes stiffness-proportional damping only");
  expect_scene_error(head + "}\n" + tail + "outputs:\n  m: {body: bar, quantities: [modal_coordinates]}\n", 5,
                     "output 'm': body 'bar' is modes: full, which has no modal coordinates");
  expect_scene_error(head + "}\n" + tail + "paraview: {stresses: true}\n", 4,
                     "paraview: body 'bar' is modes: full, whose stresses fbsim does not recover");
}
