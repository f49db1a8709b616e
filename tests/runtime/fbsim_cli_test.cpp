// fbsim as a user runs it: the issue's scene on a bar made by fbprep, and bad scenes that must each give one
// error line naming the scene line, exit code 2 and no crash.
#include "cli_run.hpp"
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

using flexbody::test::CliRun;
using flexbody::test::run_fbprep;
using flexbody::test::run_fbsim;
using flexbody::test::write_text;

namespace {

// A 1 x 0.05 x 0.05 m steel bar with rbe3 interfaces root (x = 0) and tip (x = 1), 8 modes.
const std::filesystem::path& bar_folder() {
  static const std::filesystem::path dir = [] {
    const auto d = flexbody::test::scratch_dir();
    write_text(d / "bar.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 0.05, 0.05};\n");
    write_text(d / "bar.yaml", R"(input: bar.geo
unit: m
mesh: {size: 0.025}
reduction: {modes: 8}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}}
  tip: {select: {plane: {point: [1, 0, 0], normal: [1, 0, 0]}}}
)");
    const CliRun prep = run_fbprep(d, "bar.yaml -o bar.fbh5 -q");
    EXPECT_EQ(prep.exit_code, 0) << prep.err;
    return d;
  }();
  return dir;
}

const char* kIssueScene = R"(bodies:
  bar: {file: bar.fbh5, modes: 8}
joints:
  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}
gravity: [0, -9.81, 0]
integrator: {type: generalized-alpha, rho_inf: 0.9, step: 1.0e-4, end: 2.0}
outputs:
  tip: {body: bar, interface: tip, quantities: [position]}
)";

void expect_scene_error(const std::string& scene, int line, const std::string& message) {
  SCOPED_TRACE(scene);
  const auto& dir = bar_folder();
  write_text(dir / "bad.yaml", scene);
  const CliRun run = run_fbsim(dir, "bad.yaml -o bad_out -q");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("fbsim: error: bad.yaml:" + std::to_string(line) + ": " + message), std::string::npos) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
}

}  // namespace

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

namespace {

std::vector<std::vector<double>> csv_numbers(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<double>> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

double von_mises_of_voigt(const double* s) {  // xx, yy, zz, xy, xz, yz
  return std::sqrt(0.5 * ((s[0] - s[1]) * (s[0] - s[1]) + (s[1] - s[2]) * (s[1] - s[2]) + (s[2] - s[0]) * (s[2] - s[0])) +
                   3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

}  // namespace

TEST(FbsimCli, ParaViewSeriesAgreesWithTheCsvOutputs) {
  // The swinging bar of the test above, drawn every 5 steps. The series and the CSV files compute the same
  // quantities by different paths (surface arrays vs marker rows and region stress modes), so they must agree to
  // round-off: a surface node's position with a node marker's, the norm of its world displacement with the
  // region's body-axes displacement, its von Mises stress (rotation invariant) with the region's stress.
  const auto& dir = bar_folder();
  const auto body = flexbody::format::read_body_file(dir / "bar.fbh5");
  std::vector<int> surface(body.mesh.surface_triangles.data(),
                           body.mesh.surface_triangles.data() + body.mesh.surface_triangles.size());
  std::sort(surface.begin(), surface.end());
  surface.erase(std::unique(surface.begin(), surface.end()), surface.end());
  const int node = body.interfaces[1].nodes(0);  // a node of the tip face: on the surface, and it moves most
  const auto local = std::lower_bound(surface.begin(), surface.end(), node) - surface.begin();
  ASSERT_EQ(surface[static_cast<std::size_t>(local)], node);
  write_text(dir / "movie.yaml", R"(bodies:
  bar: {file: bar.fbh5, modes: 4}
joints:
  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}
gravity: [0, -9.81, 0]
integrator: {step: 1.0e-3, end: 0.02}
outputs:
  whole: {body: bar, region: body, quantities: [displacement, stress]}
  corner: {body: bar, node: )" + std::to_string(node) + R"(, quantities: [position]}
paraview: {every: 5}
)");
  const CliRun run = run_fbsim(dir, "movie.yaml -o movie_out --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string pvd = flexbody::test::slurp(dir / "movie_out" / "bar.pvd");
  for (int frame = 0; frame <= 4; ++frame) {  // t = 0, 5, 10, 15, 20 ms
    const std::string file = "bar/bar_00000" + std::to_string(frame) + ".vtu";
    EXPECT_NE(pvd.find("file=\"" + file + "\""), std::string::npos) << file;
    EXPECT_TRUE(std::filesystem::exists(dir / "movie_out" / file)) << file;
  }
  EXPECT_NE(pvd.find("timestep=\"0.02\""), std::string::npos) << pvd;
  EXPECT_EQ(pvd.find("bar_000005"), std::string::npos);

  const std::string vtu = flexbody::test::slurp(dir / "movie_out" / "bar" / "bar_000004.vtu");
  const auto points = flexbody::test::vtu_values<double>(vtu, "Points");
  const auto displacement = flexbody::test::vtu_values<double>(vtu, "displacement");
  const auto mises = flexbody::test::vtu_values<double>(vtu, "von_mises");
  const auto stress = flexbody::test::vtu_values<double>(vtu, "stress");
  const auto triangles = flexbody::test::vtu_values<std::int64_t>(vtu, "connectivity");
  ASSERT_EQ(points.size(), 3 * surface.size());
  ASSERT_EQ(displacement.size(), 3 * surface.size());
  ASSERT_EQ(mises.size(), surface.size());
  ASSERT_EQ(stress.size(), 6 * surface.size());
  ASSERT_EQ(triangles.size(), 3 * static_cast<std::size_t>(body.mesh.surface_triangles.rows()));

  const auto corner = csv_numbers(dir / "movie_out" / "corner.csv").back();
  ASSERT_NEAR(corner[0], 0.02, 1e-15);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(points[3 * local + k], corner[1 + k], 1e-13);  // m, on a 1 m bar
  const auto whole = csv_numbers(dir / "movie_out" / "whole.csv").back();
  const std::size_t n_n = static_cast<std::size_t>(body.mesh.nodes.rows());
  ASSERT_EQ(whole.size(), 1 + 9 * n_n);  // the region "body" holds every node, in order
  const double* u_bar = &whole[1 + 3 * static_cast<std::size_t>(node)];
  const double* sigma_bar = &whole[1 + 3 * n_n + 6 * static_cast<std::size_t>(node)];
  const double u_norm = std::sqrt(u_bar[0] * u_bar[0] + u_bar[1] * u_bar[1] + u_bar[2] * u_bar[2]);
  const double series_u = std::sqrt(displacement[3 * local] * displacement[3 * local] +
                                    displacement[3 * local + 1] * displacement[3 * local + 1] +
                                    displacement[3 * local + 2] * displacement[3 * local + 2]);
  EXPECT_GT(u_norm, 1e-7);  // m: the tip lags the rigid swing measurably
  EXPECT_NEAR(series_u, u_norm, 1e-12 * u_norm + 1e-18);
  const double expected_mises = von_mises_of_voigt(sigma_bar);
  EXPECT_GT(expected_mises, 1.0);  // Pa
  EXPECT_NEAR(mises[static_cast<std::size_t>(local)], expected_mises, 1e-9 * expected_mises);
  // The world-axes tensor has the body-axes tensor's invariants: its trace.
  const double* s = &stress[6 * static_cast<std::size_t>(local)];
  EXPECT_NEAR(s[0] + s[1] + s[2], sigma_bar[0] + sigma_bar[1] + sigma_bar[2], 1e-9 * expected_mises);
}

TEST(ParaViewSeries, RefusesStressesThatTheBodyFileDoesNotRecover) {
  // A region that leaves surface nodes out cannot colour the surface: one clear error, not zeros or NaN. Without
  // stresses the same body is drawn.
  const auto body = flexbody::format::read_body_file(bar_folder() / "bar.fbh5");
  flexbody::runtime::BodyModel model = flexbody::runtime::make_body_model(body, 2, "bar.fbh5");
  auto& region = model.recovery.at(0);
  const Eigen::Index half = region.nodes.size() / 2;
  region.nodes.conservativeResize(half);
  region.stress_modes.conservativeResize(6 * half, Eigen::NoChange);
  try {
    const flexbody::runtime::ParaViewSeries series(bar_folder() / "refused", "bar", model, true);
    ADD_FAILURE() << "accepted a partial stress recovery";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bar.fbh5: its output regions recover stresses at "), std::string::npos) << e.what();
  }
  const flexbody::runtime::ParaViewSeries series(bar_folder() / "drawn", "bar", model, false);
  EXPECT_FALSE(series.writes_stresses());
  EXPECT_FALSE(std::filesystem::exists(bar_folder() / "refused"));
}

TEST(ParaViewSeries, DrawsRotatedBodiesInWorldAxes) {
  // A deformed bar at a general orientation: every component of the written positions, displacements and stress
  // tensors must equal τ + A(X̄ + ū), A ū and A σ̄ Aᵀ computed here from the body file's fields and stress modes
  // (ū_i = Σ_f Ῡ'_f(i) ξ̄_f, σ̄ = S ξ̄), in ParaView's XX, YY, ZZ, XY, YZ, XZ order. A rotation far from the
  // identity catches A swapped with Aᵀ and swapped shear components, which invariants would not.
  const auto body = flexbody::format::read_body_file(bar_folder() / "bar.fbh5");
  const flexbody::runtime::BodyModel model = flexbody::runtime::make_body_model(body, 4, "bar.fbh5");
  const Eigen::Index n_f = model.field_count();
  const Eigen::Matrix3d a = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d tau(0.1, -0.2, 0.3);
  Eigen::VectorXd xi_bar(3 * n_f);
  for (Eigen::Index f = 0; f < n_f; ++f)  // modes 1 and 3 with amplitudes 1e-3 and -5e-4 kg^1/2 m
    xi_bar.segment<3>(3 * f) = 1e-3 * model.mode_coefficients.block<1, 3>(f, 0).transpose() -
                               5e-4 * model.mode_coefficients.block<1, 3>(f, 6).transpose();
  Eigen::VectorXd q_b(12 + 3 * n_f);
  q_b.head<3>() = tau;
  q_b.segment<9>(3) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(a.data());
  for (Eigen::Index f = 0; f < n_f; ++f) q_b.segment<3>(12 + 3 * f) = a * xi_bar.segment<3>(3 * f);

  const auto dir = flexbody::test::scratch_dir();
  flexbody::runtime::ParaViewSeries series(dir, "bar", model, true);
  series.write(0.5, q_b);
  EXPECT_NE(flexbody::test::slurp(dir / "bar.pvd").find("timestep=\"0.5\" part=\"0\" file=\"bar/bar_000000.vtu\""),
            std::string::npos);
  const std::string vtu = flexbody::test::slurp(dir / "bar" / "bar_000000.vtu");
  const auto points = flexbody::test::vtu_values<double>(vtu, "Points");
  const auto displacement = flexbody::test::vtu_values<double>(vtu, "displacement");
  const auto stress = flexbody::test::vtu_values<double>(vtu, "stress");
  std::vector<int> surface(body.mesh.surface_triangles.data(),
                           body.mesh.surface_triangles.data() + body.mesh.surface_triangles.size());
  std::sort(surface.begin(), surface.end());
  surface.erase(std::unique(surface.begin(), surface.end()), surface.end());
  ASSERT_EQ(points.size(), 3 * surface.size());
  ASSERT_EQ(stress.size(), 6 * surface.size());
  const auto& region = model.recovery.at(0);  // "body": every node
  double worst_position = 0.0, worst_displacement = 0.0, worst_stress = 0.0, largest_u = 0.0, largest_stress = 0.0;
  for (std::size_t j = 0; j < surface.size(); ++j) {
    const int i = surface[j];
    Eigen::Vector3d u_bar = Eigen::Vector3d::Zero();
    for (Eigen::Index f = 0; f < n_f; ++f) u_bar += model.fields(i, f) * xi_bar.segment<3>(3 * f);
    const Eigen::Vector3d u = a * u_bar, r = tau + a * (model.nodes.row(i).transpose() + u_bar);
    const auto at = std::find(region.nodes.data(), region.nodes.data() + region.nodes.size(), i) - region.nodes.data();
    ASSERT_LT(at, region.nodes.size());
    const Eigen::Matrix<double, 6, 1> v = region.stress_modes.middleRows<6>(6 * at) * xi_bar;  // xx yy zz xy xz yz
    Eigen::Matrix3d s_bar;
    s_bar << v(0), v(3), v(4), v(3), v(1), v(5), v(4), v(5), v(2);
    const Eigen::Matrix3d s = a * s_bar * a.transpose();
    const double expected_stress[6] = {s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(1, 2), s(0, 2)};
    for (int k = 0; k < 3; ++k) {
      worst_position = std::max(worst_position, std::abs(points[3 * j + k] - r(k)));
      worst_displacement = std::max(worst_displacement, std::abs(displacement[3 * j + k] - u(k)));
    }
    for (int k = 0; k < 6; ++k) worst_stress = std::max(worst_stress, std::abs(stress[6 * j + k] - expected_stress[k]));
    largest_u = std::max(largest_u, u.norm());
    largest_stress = std::max(largest_stress, s.norm());
  }
  EXPECT_GT(largest_u, 1e-4);       // m: the state is visibly deformed
  EXPECT_GT(largest_stress, 1e5);   // Pa
  EXPECT_LT(worst_position, 4e-15);  // m: a few ulps of coordinates below 2 m (the same sums, ordered differently)
  EXPECT_LT(worst_displacement, 1e-12 * largest_u);
  EXPECT_LT(worst_stress, 1e-12 * largest_stress);
}

// Issue 12, item 6: a conservative scene that gains energy or angular momentum must not pass silently. A free rigid
// plate (0.3 x 0.2 x 0.01 m) spinning at 5 rad/s near its intermediate principal axis with ρ∞ = 0.99 and h = 2 ms,
// integrated in the index-3 form (`constraints: index3`), gains energy: the quadratic orthogonality constraints
// without their velocity rows are weakly unstable near ρ∞ = 1 (item 5). At 6.93 s it has gained 0.1 % of its
// kinetic energy, and its angular momentum 0.1 % at 7.33 s, in an oscillation of period 2 h (see kCheckEvery). On
// 521de58 the same run (then the only form) exited 0 without a word (a 12 s run ended at +17.6 %).
// With ρ∞ = 0.9 it does not gain. This needs the GCMS's rigid body (τ and A, `formulation: gcms`); a rigid body's
// default, position and Euler parameters (7 coordinates, one quadratic row), gains nothing at ρ∞ = 0.99: 6.7e-8.
TEST(FbsimCli, AConservativeSceneThatGainsEnergyIsFlagged) {
  const auto dir = flexbody::test::scratch_dir();
  write_text(dir / "plate.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 0.3, 0.2, 0.01};\n");
  write_text(dir / "plate.yaml", "input: plate.geo\nunit: m\nmesh: {size: 0.05}\nreduction: {modes: 1}\noutput_regions: {}\n");
  const CliRun prep = run_fbprep(dir, "plate.yaml -o plate.fbh5 -q");
  ASSERT_EQ(prep.exit_code, 0) << prep.err;
  auto scene = [](double rho, const std::string& formulation = ", formulation: gcms") {
    return "bodies:\n  plate: {file: plate.fbh5, modes: rigid" + formulation + ", angular_velocity: [0.05, 5.0, 0.05]}\n"
           "integrator: {type: generalized-alpha, rho_inf: " + std::to_string(rho) +
           ", step: 2.0e-3, end: 8.0, constraints: index3}\n";
  };
  write_text(dir / "flip.yaml", scene(0.99));
  const CliRun run = run_fbsim(dir, "flip.yaml -o flip_out --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json summary = nlohmann::json::parse(run.out);
  EXPECT_TRUE(summary["conserves_energy"].get<bool>());
  EXPECT_TRUE(summary["conserves_angular_momentum"].get<bool>());
  EXPECT_EQ(summary["conservation_warnings"].get<int>(), 2) << run.err;
  EXPECT_GT(summary["energy_growth"].get<double>(), 1e-3);
  EXPECT_GT(summary["angular_momentum_growth"].get<double>(), 1e-3);
  EXPECT_NE(run.err.find("fbsim: warning: t = 6.9"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("the energy of this conservative scene"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("the angular momentum about the centre of mass"), std::string::npos) << run.err;

  write_text(dir / "damped.yaml", scene(0.9));
  const CliRun damped = run_fbsim(dir, "damped.yaml -o damped_out --json");
  ASSERT_EQ(damped.exit_code, 0) << damped.err;
  const nlohmann::json quiet = nlohmann::json::parse(damped.out);
  EXPECT_EQ(quiet["conservation_warnings"].get<int>(), 0) << damped.err;
  EXPECT_EQ(quiet["energy_growth"].get<double>(), 0.0);          // measured: it only dissipates
  EXPECT_LT(quiet["angular_momentum_growth"].get<double>(), 1e-5);  // measured 4.2e-6
  EXPECT_TRUE(damped.err.empty()) << damped.err;

  write_text(dir / "euler.yaml", scene(0.99, ""));  // the default rigid body: Euler parameters
  const CliRun euler = run_fbsim(dir, "euler.yaml -o euler_out --json");
  ASSERT_EQ(euler.exit_code, 0) << euler.err;
  const nlohmann::json kept = nlohmann::json::parse(euler.out);
  EXPECT_EQ(kept["conservation_warnings"].get<int>(), 0) << euler.err;
  EXPECT_LT(kept["energy_growth"].get<double>(), 1e-6);            // measured 6.7e-8
  EXPECT_LT(kept["angular_momentum_growth"].get<double>(), 1e-6);  // measured 3.3e-8
}

// The conservation checks apply only where the laws hold: a pendulum on a joint to ground conserves energy but
// not angular momentum; a body with a force, or with damping, conserves neither.
TEST(FbsimCli, ConservationChecksApplyWhereTheLawsHold) {
  const auto& dir = bar_folder();
  std::string pendulum = kIssueScene;
  pendulum.replace(pendulum.find("end: 2.0"), 8, "end: 0.05");
  write_text(dir / "conserving.yaml", pendulum);
  const CliRun run = run_fbsim(dir, "conserving.yaml -o conserving_out --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json summary = nlohmann::json::parse(run.out);
  EXPECT_TRUE(summary["conserves_energy"].get<bool>());
  EXPECT_FALSE(summary["conserves_angular_momentum"].get<bool>());
  EXPECT_EQ(summary["conservation_warnings"].get<int>(), 0);
  EXPECT_GT(summary["integrator_us_per_step"].get<double>(), 0.0);
  EXPECT_GE(summary["us_per_step"].get<double>(), summary["integrator_us_per_step"].get<double>());
  write_text(dir / "pushed.yaml", pendulum + "forces:\n  push: {body: bar, interface: tip, force: [0, -10, 0]}\n");
  const nlohmann::json pushed = nlohmann::json::parse(run_fbsim(dir, "pushed.yaml -o pushed_out --json").out);
  EXPECT_FALSE(pushed["conserves_energy"].get<bool>());
  std::string damped = pendulum;
  damped.replace(damped.find("modes: 8}"), 9, "modes: 8, damping: {modal: 0.02}}");
  write_text(dir / "damped.yaml", damped);
  const nlohmann::json damped_run = nlohmann::json::parse(run_fbsim(dir, "damped.yaml -o damped_out --json").out);
  EXPECT_FALSE(damped_run["conserves_energy"].get<bool>());
}

// Round-off never warns (helper review of 4a1edd3): a body that only translates has |L_0| of round-off, against
// which any round-off grows by a lot (this gliding bar: +137 % on 4a1edd3); a pendulum released 1e-4° from hanging
// exchanges ~1e-13 of its gravity potential, so one ULP of that potential can look like growth (the review's plate
// pendulum: +166 %). The growth is now measured against at least 1e-9 of the magnitudes of the terms summed.
TEST(FbsimCli, RoundOffOfTheConservedQuantitiesDoesNotWarn) {
  const auto& dir = bar_folder();
  write_text(dir / "gliding.yaml", R"(bodies:
  bar: {file: bar.fbh5, modes: rigid, position: [3.1, 1.7, 2.3], rotation: {axis: [1, 2, 3], angle_deg: 37},
        velocity: [1.3, 2.1, 0.5]}
integrator: {type: generalized-alpha, rho_inf: 0.9, step: 1.0e-3, end: 0.5}
)");
  const CliRun gliding = run_fbsim(dir, "gliding.yaml -o gliding_out --json");
  ASSERT_EQ(gliding.exit_code, 0) << gliding.err;
  const nlohmann::json glide = nlohmann::json::parse(gliding.out);
  EXPECT_TRUE(glide["conserves_angular_momentum"].get<bool>());
  EXPECT_EQ(glide["conservation_warnings"].get<int>(), 0) << gliding.err;
  EXPECT_LT(glide["angular_momentum_growth"].get<double>(), 1e-3);

  write_text(dir / "hanging.yaml", R"(bodies:
  bar: {file: bar.fbh5, modes: 8, rotation: {axis: [0, 0, 1], angle_deg: -89.9999}}
joints:
  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}
gravity: [0, -9.81, 0]
integrator: {type: generalized-alpha, rho_inf: 0.9, step: 1.0e-4, end: 0.05}
)");
  const CliRun hanging = run_fbsim(dir, "hanging.yaml -o hanging_out --json");
  ASSERT_EQ(hanging.exit_code, 0) << hanging.err;
  const nlohmann::json hang = nlohmann::json::parse(hanging.out);
  EXPECT_TRUE(hang["conserves_energy"].get<bool>());
  EXPECT_EQ(hang["conservation_warnings"].get<int>(), 0) << hanging.err;
  EXPECT_LT(hang["energy_growth"].get<double>(), 1e-3);
}

// Issue 13: `step: 1e-300` took no step (lround of 1e300) and reported success with the t = 0 row; `step: 1e-20`
// would run 1e17 steps. A step count beyond kMostSteps is refused at the step's line, with the count.
TEST(FbsimCli, StepsBeyondTheLimitAreRefused) {
  const std::string head = "bodies:\n  bar: {file: bar.fbh5, modes: 2}\n";
  expect_scene_error(head + "integrator: {step: 1.0e-300, end: 1}\n", 3,
                     "integrator step 1e-300 s would take 1e+300 steps to the end time 1 s; at most 1e+09 are allowed");
  expect_scene_error(head + "integrator:\n  end: 1\n  step: 1.0e-20\n", 5,
                     "integrator step 1e-20 s would take 1e+20 steps to the end time 1 s; at most 1e+09 are allowed");
  expect_scene_error(head + "integrator: {step: 0, end: 1}\n", 3, "integrator step must be positive, got 0");
  expect_scene_error(head + "integrator: {step: .inf, end: 1}\n", 3, "integrator step must be finite, got '.inf'");
  EXPECT_FALSE(std::filesystem::exists(bar_folder() / "bad_out"));
}

namespace {

// The t column of an output file.
std::vector<double> times_of(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // the header
  std::vector<double> times;
  while (std::getline(in, line)) times.push_back(std::stod(line.substr(0, line.find(','))));
  return times;
}

}  // namespace

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
