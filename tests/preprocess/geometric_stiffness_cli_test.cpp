// fbprep --geometric-stiffness and the body spec's geometric_stiffness: true (issue 29, step 1): the cases written,
// what inspect says of them, and the spin stiffening of a free beam's first mode against Euler-Bernoulli theory.
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include "flexbody/format/body_file.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>

namespace {

using flexbody::test::CliRun;
using flexbody::test::run_fbprep;

std::filesystem::path beam_geo() { return flexbody::test::data_dir() / "gmsh-beam" / "beam_1m.geo"; }

// Mode 1 of a free-free beam spun at Ω about an axis across it through its centre of mass: the centrifugal tension
// N(x) = ρ A Ω² ((L/2)² − (x − L/2)²)/2 raises ω₁² by S Ω², S = ∫ N φ'² dx / (Ω² ∫ ρ A φ² dx) = 3.0498 for the
// Euler-Bernoulli mode φ (β L = 4.7300; by quadrature, independent of L, E and the section). The 3D beam of
// 1 x 0.05 x 0.05 m, quadratic tetrahedra of 0.05 m: 3.0416 and 3.0316 measured (about y and z: mode 1 is one of a
// degenerate pair, bending in a mix of both); Timoshenko's shear flattens the mode near its ends. 1 % asserted.
// A spin about the beam's own axis stretches it across only: S = 0.0101 measured, about (h/L)² of the others.
constexpr double kSouthwellFreeFree = 3.0498;

TEST(GeometricStiffnessCli, AFreeBeamStiffensUnderSpinAsBeamTheorySays) {
  const auto dir = flexbody::test::scratch_dir();
  const CliRun run = run_fbprep(dir, fmt::format("'{}' --unit m --mesh-size 0.05 --modes 2 --geometric-stiffness "
                                                 "-o beam.fbh5 --json", beam_geo().string()));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json prep = nlohmann::json::parse(run.out);
  const std::vector<std::string> centrifugal = {"centrifugal:xx", "centrifugal:yy", "centrifugal:zz",
                                                "centrifugal:xy", "centrifugal:xz", "centrifugal:yz"};
  EXPECT_EQ(prep["geometric_stiffness_cases"].get<std::vector<std::string>>(), centrifugal);  // no interfaces
  EXPECT_LT(prep["geometric_stiffness_solves"]["max_relative_residual"].get<double>(), 1e-8);
  EXPECT_GT(prep["geometric_stiffness_solves"]["iterations"].get<int>(), 0);

  const CliRun inspect = run_fbprep(dir, "inspect beam.fbh5 --json");
  ASSERT_EQ(inspect.exit_code, 0) << inspect.err;
  const nlohmann::json j = nlohmann::json::parse(inspect.out);
  EXPECT_EQ(j["geometric_stiffness_cases"].get<std::vector<std::string>>(), centrifugal);
  const auto s = j["spin_stiffening_mode_1"].get<std::vector<double>>();
  ASSERT_EQ(s.size(), 3u);
  EXPECT_NEAR(s[1] / kSouthwellFreeFree, 1.0, 0.01);
  EXPECT_NEAR(s[2] / kSouthwellFreeFree, 1.0, 0.01);
  EXPECT_GT(s[0], 0.0);
  EXPECT_LT(s[0], 0.01 * s[1]);
  const CliRun report = run_fbprep(dir, "inspect beam.fbh5");
  EXPECT_NE(report.out.find("cases                 6: centrifugal (6)"), std::string::npos) << report.out;
  EXPECT_NE(report.out.find("mode 1 under spin     omega_1^2 + S Omega^2 with S = "), std::string::npos) << report.out;

  // Without the flag nothing of it is written, and the body is otherwise the same.
  const CliRun plain = run_fbprep(dir, fmt::format("'{}' --unit m --mesh-size 0.05 --modes 2 -o plain.fbh5 --json",
                                                   beam_geo().string()));
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_TRUE(nlohmann::json::parse(plain.out)["geometric_stiffness_cases"].empty());
  const auto with = flexbody::format::read_body_file(dir / "beam.fbh5");
  const auto without = flexbody::format::read_body_file(dir / "plain.fbh5");
  EXPECT_TRUE(without.geometric_stiffness.empty());
  EXPECT_EQ(with.gcms.stiffness, without.gcms.stiffness);
  EXPECT_EQ(with.modes.frequencies_hz, without.modes.frequencies_hz);
  const CliRun plain_inspect = run_fbprep(dir, "inspect plain.fbh5 --json");
  EXPECT_TRUE(nlohmann::json::parse(plain_inspect.out)["spin_stiffening_mode_1"].is_null());
}

// A body spec asks with geometric_stiffness: true; every interface adds its six unit loads, with Craig-Bampton modes
// too (solved on a factorization of the free part: Craig-Bampton's own holds the interior only). Anything but true
// or false is refused in one line naming the key.
TEST(GeometricStiffnessCli, ABodySpecAsksForItWithInterfaceCases) {
  const auto dir = flexbody::test::scratch_dir();
  std::filesystem::copy_file(beam_geo(), dir / "beam.geo");
  const std::string spec = R"(input: beam.geo
unit: m
mesh: {size: 0.05}
reduction: {kind: craig-bampton, modes: 2}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}, coupling: rbe2}
  tip: {select: {plane: {point: [1, 0, 0], normal: [1, 0, 0]}}}
geometric_stiffness: true
)";
  flexbody::test::write_text(dir / "cb.yaml", spec);
  const CliRun run = run_fbprep(dir, "cb.yaml -o cb.fbh5 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto body = flexbody::format::read_body_file(dir / "cb.fbh5");
  ASSERT_EQ(body.geometric_stiffness.cases.size(), 18u);
  EXPECT_EQ(body.geometric_stiffness.cases[6], "root:fx");
  EXPECT_EQ(body.geometric_stiffness.cases[17], "tip:mz");
  EXPECT_EQ(body.geometric_stiffness.matrices[0].rows(), 4 + body.gcms.field_count());
  // The tip pulled along the beam (tip:fx, balanced by the beam's inertia) tensions it: the x̄ entry is the virial
  // Σ x̄ f_x of the balanced load, positive.
  EXPECT_GT(body.geometric_stiffness.matrices[12](1, 1), 0.0);
  for (const auto& [key, value] : body.provenance.options)
    if (key == "geometric_stiffness") {
      EXPECT_EQ(value, "true");
    }

  std::string bad = spec;
  bad.replace(bad.find("geometric_stiffness: true"), 25, "geometric_stiffness: yes");
  flexbody::test::write_text(dir / "bad.yaml", bad);
  const CliRun refused = run_fbprep(dir, "bad.yaml -o bad.fbh5");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  EXPECT_NE(refused.err.find("bad.yaml:8: geometric_stiffness must be true or false"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.fbh5"));
}

}  // namespace
