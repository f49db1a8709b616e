// fbsim's outputs checked against each other and against the laws they must keep: the ParaView series against the
// CSV files, the conservation checks, and the step limit.
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

namespace {

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
