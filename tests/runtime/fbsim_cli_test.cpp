// fbsim as a user runs it: the issue's scene on a bar made by fbprep, assembly, a four-bar's redundant rows, bad
// scenes that must each give one error line naming the scene line (exit code 2, no crash), and region outputs.
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


TEST(FbsimCli, TheIssuesPendulumSceneRuns) {
  // The issue's scene, shortened to 0.05 s (500 steps) to keep the test quick; the shape is unchanged.
  const auto& dir = bar_folder();
  std::string scene = kIssueScene;
  scene.replace(scene.find("end: 2.0"), 8, "end: 0.05");
  write_text(dir / "scene.yaml", scene);
  const CliRun run = run_fbsim(dir, "scene.yaml -o out --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["steps"], 500);
  EXPECT_GE(json["newton_iterations"].get<int>(), 500);
  // The joint holds to the Newton tolerance (its rows are O(1) lengths and directions).
  EXPECT_LT(json["max_constraint_residual"].get<double>(), 1e-9);
  std::ifstream tip(dir / "out" / "tip.csv");
  std::string header, first, line, last;
  std::getline(tip, header);
  std::getline(tip, first);
  while (std::getline(tip, line)) last = line;
  EXPECT_EQ(header, "t [s],x [m],y [m],z [m]");
  // The tip starts at the bar's end (x = 1, y and z at the face centre) and falls: after 0.05 s a rigid bar
  // from horizontal has turned by about (3g / 2L) t² / 2 = 0.018 rad, so y has dropped by about 1.8 cm.
  double t0, x0, y0, z0, t1, x1, y1, z1;
  char c;
  std::istringstream(first) >> t0 >> c >> x0 >> c >> y0 >> c >> z0;
  std::istringstream(last) >> t1 >> c >> x1 >> c >> y1 >> c >> z1;
  EXPECT_NEAR(x0, 1.0, 1e-9);
  EXPECT_NEAR(t1, 0.05, 1e-12);
  EXPECT_NEAR(y0 - y1, 0.0184, 0.002);
}

// Two bars, the second's root pinned to the first's tip, placed `offset` m along x beyond it: the initial assembly
// closes a mesh-sized gap, reports it, and refuses a gap of a tenth of a bar naming the joint.
std::string two_bars(double offset) {
  return "bodies:\n  first: {file: bar.fbh5, modes: 4}\n  second: {file: bar.fbh5, modes: 4, position: [" +
         std::to_string(1.0 + offset) + ", 0, 0]}\njoints:\n"
         "  pivot: {type: revolute, body: first, interface: root, to: ground, axis: [0, 0, 1]}\n"
         "  link: {type: revolute, body: second, interface: root, to: {body: first, interface: tip}, axis: [0, 0, 1]}\n"
         "gravity: [0, -9.81, 0]\nintegrator: {type: generalized-alpha, step: 1.0e-3, end: 0.01}\n";
}

TEST(FbsimCli, AssemblesAMicrometreGapAndRefusesATenthOfABar) {
  const auto& dir = bar_folder();
  write_text(dir / "gap.yaml", two_bars(5e-6));
  const CliRun run = run_fbsim(dir, "gap.yaml -o gap_out --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto assembly = nlohmann::json::parse(run.out)["assembly"];
  EXPECT_GE(assembly["iterations"].get<int>(), 1);
  EXPECT_NEAR(assembly["largest_gap_m"].get<double>(), 5e-6, 1e-9);  // the position's rounding, to_string's 6 digits
  ASSERT_EQ(assembly["moves_m"].size(), 2u);
  // The two bars share the 5 µm: each moves by part of it, with the lever of its turn about the pivot.
  for (const auto& move : assembly["moves_m"]) EXPECT_LT(move.get<double>(), 2 * 5e-6);
  EXPECT_GT(assembly["largest_move_m"].get<double>(), 1e-6);
  expect_scene_error(two_bars(0.1), 6,
                     "joint 'link': its markers second/root and first/tip are 0.1 m apart; closing them moves body");
}

TEST(FbsimCli, AFourBarRunsWithItsRedundantRowsLeftOutAndNamed) {
  // A parallelogram of three rigid bars, the crank and the rocker at 60°, falling under gravity: four revolute
  // joints about z repeat three rows (issue 27, item 4). The last joint gives them up, and the summary says which:
  // the translation normal to the plane and the two tilts of the axis. (The bar's input frame has its origin at a
  // corner: the coupler sits where its root face's centre, (0, 0.025, 0.025) in it, meets the crank's tip face's.)
  // With flexible bars nothing repeats: their modes bend and twist out of the plane, and take those rows up.
  const auto& dir = bar_folder();
  auto scene = [](const std::string& modes) {
    return "bodies:\n"
           "  crank: {file: bar.fbh5, modes: " + modes + ", rotation: {axis: [0, 0, 1], angle_deg: 60}}\n"
           "  coupler: {file: bar.fbh5, modes: " + modes + ", position: [0.4783493649053890, 0.8535254037844386, 0]}\n"
           "  rocker: {file: bar.fbh5, modes: " + modes + ", position: [1, 0, 0], rotation: {axis: [0, 0, 1], angle_deg: 60}}\n"
           "joints:\n"
           "  A: {type: revolute, body: crank, interface: root, to: ground, axis: [0, 0, 1]}\n"
           "  B: {type: revolute, body: coupler, interface: root, to: {body: crank, interface: tip}, axis: [0, 0, 1]}\n"
           "  C: {type: revolute, body: coupler, interface: tip, to: {body: rocker, interface: tip}, axis: [0, 0, 1]}\n"
           "  D: {type: revolute, body: rocker, interface: root, to: ground, axis: [0, 0, 1]}\n"
           "gravity: [0, -9.81, 0]\nintegrator: {step: 1.0e-3, end: 0.05}\n";
  };
  write_text(dir / "four_bar.yaml", scene("rigid"));
  write_text(dir / "flexible_four_bar.yaml", scene("4"));
  const CliRun flexible = run_fbsim(dir, "flexible_four_bar.yaml -o flexible_four_bar_out --json");
  ASSERT_EQ(flexible.exit_code, 0) << flexible.err;
  EXPECT_TRUE(nlohmann::json::parse(flexible.out)["removed_constraints"].empty()) << flexible.out;
  const CliRun run = run_fbsim(dir, "four_bar.yaml -o four_bar_out --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = nlohmann::json::parse(run.out);
  const auto removed = summary["removed_constraints"];
  ASSERT_EQ(removed.size(), 3u) << run.out;
  const std::vector<std::pair<int, std::string>> expected = {
      {3, "translation along z"}, {4, "rotation about [1.00, 0.00, 0.00]"}, {5, "rotation about [0.00, 1.00, 0.00]"}};
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(removed[k]["joint"], "D");
    EXPECT_EQ(removed[k]["row"].get<int>(), expected[k].first);
    EXPECT_EQ(removed[k]["meaning"], expected[k].second);
  }
  EXPECT_LT(summary["max_constraint_residual"].get<double>(), 1e-9);  // the kept rows hold to the Newton tolerance
  const CliRun text = run_fbsim(dir, "four_bar.yaml -o four_bar_out");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("joint 'D': redundant rows left out (translation along z; rotation about [1.00, 0.00, 0.00]; "
                          "rotation about [0.00, 1.00, 0.00]): the other joints carry them"),
            std::string::npos)
      << text.out;
  // Two joints at one interface that hold the same point: the spherical joint's three rows repeat the revolute's.
  write_text(dir / "twice.yaml", "bodies:\n  bar: {file: bar.fbh5, modes: 2}\njoints:\n"
                                 "  a: {type: revolute, body: bar, interface: root, axis: [0, 0, 1]}\n"
                                 "  b: {type: spherical, body: bar, interface: root}\n"
                                 "gravity: [0, -9.81, 0]\nintegrator: {step: 1.0e-3, end: 0.01}\n");
  const CliRun twice = run_fbsim(dir, "twice.yaml -o twice_out --json");
  ASSERT_EQ(twice.exit_code, 0) << twice.err;
  const auto twice_removed = nlohmann::json::parse(twice.out)["removed_constraints"];
  ASSERT_EQ(twice_removed.size(), 3u);
  for (const auto& c : twice_removed) EXPECT_EQ(c["joint"], "b");
}

TEST(FbsimCli, BadScenesNameTheLine) {
  const std::string head = "bodies:\n  bar: {file: bar.fbh5, modes: 2}\n";
  const std::string tail = "integrator: {step: 1.0e-3, end: 0.01}\n";
  expect_scene_error(head + "colour: red\n" + tail, 3, "unknown key 'colour' in the scene");
  expect_scene_error(head + "joints:\n  pin: {type: revolute, body: wheel, interface: root, axis: [0, 0, 1]}\n" + tail, 4,
                     "joint 'pin': no body 'wheel' in the scene");
  expect_scene_error(head + "joints:\n  pin: {type: revolute, body: bar, interface: hub, axis: [0, 0, 1]}\n" + tail, 4,
                     "joint 'pin': bar.fbh5: no interface 'hub' (interfaces: root, tip)");
  expect_scene_error(head + "gravity: [0, .nan, 0]\n" + tail, 3, "gravity must be finite, got '.nan'");
  expect_scene_error(head + "integrator: {step: 0.1, end: 0.01}\n", 3,
                     "integrator step 0.1 s is larger than the end time 0.01 s");
  expect_scene_error("bodies:\n  bar: {file: bar.fbh5, modes: 99}\n" + tail, 2, "bar.fbh5: 99 modes asked for, the file holds 8");
  expect_scene_error(head + "outputs:\n  tip: {body: bar, interface: tip, quantities: [stress]}\n" + tail, 4,
                     "output 'tip': quantity 'stress' is not available here; use position, velocity");
  expect_scene_error("bodies:\n  bar: {file: missing.fbh5}\n" + tail, 2, "missing.fbh5");
  expect_scene_error(head + "springs:\n  s: {from: {body: bar, interface: tip}, to: {ground: [1, 0, 0]}, stiffness: -1}\n" +
                         tail, 4, "spring 's': stiffness, damping and length must be >= 0");
  expect_scene_error(head + "forces:\n  f: {body: bar, interface: tip}\n" + tail, 4, "force 'f' needs force or torque");
  expect_scene_error(head + "paraview: {bodies: [wheel]}\n" + tail, 3, "paraview: no body 'wheel' in the scene");
  expect_scene_error(head + "paraview: {every: 0}\n" + tail, 3, "paraview every must be at least 1");
  expect_scene_error(head + "integrator: {step: 1.0e-3, end: 0.01, tolerance: 1.0e-2}\n", 3,
                     "integrator tolerance 0.01 is above 0.001: it is relative to each step's predictor-corrector");
  expect_scene_error(head + "integrator: {step: 1.0e-3, end: 0.01, min_step: 2.0e-3}\n", 3,
                     "integrator min_step 0.002 s is larger than the step 0.001 s");
  expect_scene_error(head + "integrator: {step: 1.0e-3, end: 0.01, min_step: 0}\n", 3, "integrator min_step");
  // Ranges the integrator checks itself (check_options), reported at the key's line.
  expect_scene_error(head + "integrator:\n  step: 1.0e-3\n  end: 0.01\n  rho_inf: 1.5\n", 6,
                     "integrator rho_inf must lie in [0, 1], got 1.5");
  expect_scene_error(head + "integrator:\n  step: 1.0e-3\n  end: 0.01\n  max_iterations: 0\n", 6,
                     "integrator max_iterations must be at least 1, got 0");
  expect_scene_error(head + "integrator:\n  step: 1.0e-3\n  spin_limit: -1\n  end: 0.01\n", 5,
                     "integrator spin_limit must be >= 0 (a multiple of the lowest elastic frequency; 0: no check), "
                     "got -1");
  expect_scene_error(
      head + "integrator: {step: 1.0e-3, end: 0.01, deformation_limit: -0.1}\n", 3,
      "integrator deformation_limit must be >= 0 (a fraction of the body's size; 0: no check), got -0.1");
  // step: auto (error control)
  expect_scene_error(head + "integrator: {step: auto, end: 0.01}\n", 3, "integrator step: auto needs error_tolerance");
  expect_scene_error(head + "integrator: {step: 1.0e-3, end: 0.01, error_tolerance: 1.0e-6}\n", 3,
                     "integrator error_tolerance is for step: auto (error control); this scene's step is fixed");
  expect_scene_error(head + "integrator: {step: automatic, end: 0.01}\n", 3, "integrator step must be a time in seconds or auto, got 'automatic'");
  expect_scene_error(head + "integrator: {step: auto, error_tolerance: 0, end: 0.01}\n", 3, "integrator error_tolerance");
  expect_scene_error(head + "integrator: {step: auto, error_tolerance: 1.0e-6, end: 0.01, output_every: 2}\n", 3,
                     "integrator output_every counts steps, which step: auto chooses; give output_interval (seconds)");
  expect_scene_error(head + "integrator: {step: auto, error_tolerance: 1.0e-6, end: 0.01, max_step: 1.0e-3, "
                            "initial_step: 2.0e-3}\n", 3, "integrator initial_step 0.002 s is larger than max_step 0.001 s");
  expect_scene_error(head + "integrator: {step: auto, error_tolerance: 1.0e-6, end: 0.01, max_step: 0.1}\n", 3,
                     "integrator max_step 0.1 s is larger than the end time 0.01 s");
  expect_scene_error(head + "integrator: {step: auto, error_tolerance: 1.0e-6, end: 0.01, initial_step: 1.0e-3, "
                            "min_step: 2.0e-3}\n", 3, "integrator min_step 0.002 s is larger than the initial step 0.001 s");
  expect_scene_error("bodies:\n  bar: {file: bar.fbh5, modes: full}\n"
                     "integrator: {step: auto, error_tolerance: 1.0e-6, end: 0.01}\n", 2,
                     "body 'bar' is modes: full, which step: auto cannot measure");
  expect_scene_error(head + "integrator: {step: auto, error_tolerance: 1.0e-6, end: 0.01}\nparaview: {every: 2}\n", 4,
                     "paraview every counts steps, which step: auto chooses; give interval (seconds)");
}

TEST(FbsimCli, RegionDisplacementsStressesAndOrientationsAreWritten) {
  // The bar's default output region ("body": every node, the mesh is small) and the tip's frame, over 20 ms of
  // swinging from horizontal: at t = 0 the bar is undeformed and aligned (zero displacement and stress, R = I);
  // later it bends under its own inertia, so some stress is non-zero, and every value is finite.
  const auto& dir = bar_folder();
  write_text(dir / "regions.yaml", R"(bodies:
  bar: {file: bar.fbh5, modes: 4}
joints:
  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}
gravity: [0, -9.81, 0]
integrator: {step: 1.0e-3, end: 0.02}
outputs:
  whole: {body: bar, region: body, quantities: [displacement, stress]}
  frame: {body: bar, interface: tip, quantities: [orientation]}
  pin: {joint: pivot, quantities: [reaction_force, reaction_moment]}
)");
  const CliRun run = run_fbsim(dir, "regions.yaml -o regions_out -q");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  auto rows_of = [](const std::filesystem::path& file) {
    std::ifstream in(file);
    std::vector<std::vector<std::string>> rows;
    for (std::string line; std::getline(in, line);) {
      std::vector<std::string> cells;
      std::stringstream cells_in(line);
      for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
      rows.push_back(cells);
    }
    return rows;
  };
  const auto whole = rows_of(dir / "regions_out" / "whole.csv");
  ASSERT_EQ(whole.size(), 22u);  // header, t = 0, 20 steps
  EXPECT_EQ(whole[0][1], "ux_0 [m]");
  const std::size_t nodes = (whole[0].size() - 1) / 9;
  EXPECT_EQ(whole[0][1 + 3 * nodes], "sxx_0 [Pa]");
  double largest_stress = 0.0;
  for (std::size_t c = 1; c < whole[1].size(); ++c) EXPECT_EQ(std::stod(whole[1][c]), 0.0);
  for (std::size_t c = 1 + 3 * nodes; c < whole.back().size(); ++c) {
    const double value = std::stod(whole.back()[c]);
    ASSERT_TRUE(std::isfinite(value));
    largest_stress = std::max(largest_stress, std::abs(value));
  }
  EXPECT_GT(largest_stress, 1.0);  // Pa: a swinging steel bar is stressed (kPa to MPa), far above round-off
  const auto frame = rows_of(dir / "regions_out" / "frame.csv");
  EXPECT_EQ(frame[0][1], "R11 [1]");
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(std::stod(frame[1][1 + k]), k % 4 == 0 ? 1.0 : 0.0, 1e-12);
  // The revolute joint's wrench: a force of the order of the bar's weight (19.6 kg · g), and no moment about its
  // axis z, which it releases (the rbe3 root's moment has only x and y components).
  const auto pin = rows_of(dir / "regions_out" / "pin.csv");
  ASSERT_EQ(pin[0].size(), 7u);
  EXPECT_EQ(pin[0][4], "mx [N m]");
  const double force = std::hypot(std::stod(pin.back()[1]), std::stod(pin.back()[2]), std::stod(pin.back()[3]));
  EXPECT_GT(force, 10.0);
  EXPECT_LT(std::abs(std::stod(pin.back()[6])), 1e-8 * force);
}
