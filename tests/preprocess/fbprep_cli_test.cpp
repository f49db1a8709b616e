// fbprep as a user runs it: the bundled bracket end to end, units, and every refused input (one line
// on stderr naming the problem, a non-zero exit, and no file under the output name).
#include "flexbody/format/body_file.hpp"
#include "flexbody/preprocess/eigensolver.hpp"
#include "flexbody/preprocess/stress_recovery.hpp"
#include "cli_run.hpp"
#include "test_meshes.hpp"
#include "vtu_read.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>

namespace {

using flexbody::test::CliRun;
using flexbody::test::slurp;
using flexbody::test::base64_decode;
using flexbody::test::vtu_array;

CliRun fbprep(const std::filesystem::path& dir, const std::string& arguments) {
  return flexbody::test::run_fbprep(dir, arguments);
}

// The tests below mesh it at 6 mm for speed: that mesh holds 100.7 % of the CAD solid's volume, beyond fbprep's
// default 0.5 % (issue 28), so they pass --volume-tolerance 0.01.
std::filesystem::path bracket_step() { return std::filesystem::path(FLEXBODY_SOURCE_DIR) / "meshes" / "bracket.step"; }
// A 1 x 0.05 x 0.05 box meant in metres, written by gmsh, whose STEP writer declares mm.
std::filesystem::path gmsh_beam_step() {
  return std::filesystem::path(FLEXBODY_TEST_DATA_DIR) / "gmsh-beam" / "beam_1m.step";
}

// Only the files the test itself wrote remain in `dir` (no body file, no temporary).
void expect_no_output(const std::filesystem::path& dir) {
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "stdout.txt" || name == "stderr.txt" || name.rfind("input", 0) == 0)
        << "left behind: " << name;
  }
}

void expect_refusal(const std::filesystem::path& dir, const std::string& arguments, const std::string& message) {
  SCOPED_TRACE(arguments);
  const CliRun run = fbprep(dir, arguments + " -o out.fbh5");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  EXPECT_EQ(run.err.rfind("fbprep: error: ", 0), 0u) << run.err;
  EXPECT_NE(run.err.find(message), std::string::npos) << run.err;
  expect_no_output(dir);
}

void write(const std::filesystem::path& path, const std::string& text) { flexbody::test::write_text(path, text); }

constexpr const char* kOcc = "SetFactory(\"OpenCASCADE\");\n";

}  // namespace

TEST(FbprepCli, BracketEndToEnd) {
  const auto dir = flexbody::test::scratch_dir();
  const CliRun run = fbprep(dir, fmt::format("'{}' -o bracket.fbh5 --modes 6 --json", bracket_step().string()));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // Quadratic elements by default: the first frequency's estimated error is 0.16 % (measured), far below the 5 % that
  // warns, so stderr stays empty.
  EXPECT_EQ(run.err, "");
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["element_order"], 2);
  EXPECT_LT(json["frequency_error_estimates"][0].get<double>(), 0.01);
  // Linear elements at the same default size: estimated 12 % high, beyond the 5 % error target, so fbprep meshes the
  // bracket again where the estimate puts the error (mesh_refinement.hpp): measured 3.4 %, no warning. With
  // --error-target 0 the first mesh stays, and its warning is one line naming the way out (error_estimate_test.cpp;
  // the README's Evidence measures +3.7 % at ten times the DOFs).
  const CliRun refined = fbprep(dir, fmt::format("'{}' -o linear.fbh5 --modes 1 --order 1 --json", bracket_step().string()));
  ASSERT_EQ(refined.exit_code, 0) << refined.err;
  EXPECT_EQ(refined.err, "");
  const auto refined_json = nlohmann::json::parse(refined.out);
  EXPECT_GT(refined_json["mesh_refinement"]["first_estimate"].get<double>(), 0.05);
  EXPECT_LT(refined_json["frequency_error_estimates"][0].get<double>(), 0.05);
  EXPECT_LT(refined_json["frequencies_hz"][0].get<double>(), refined_json["mesh_refinement"]["first_frequency_hz"].get<double>());
  const CliRun linear = fbprep(dir, fmt::format("'{}' -o linear.fbh5 --modes 1 --order 1 --error-target 0 --json",
                                                bracket_step().string()));
  ASSERT_EQ(linear.exit_code, 0) << linear.err;
  EXPECT_EQ(linear.err.rfind("fbprep: warning: the first frequency", 0), 0u) << linear.err;
  EXPECT_NE(linear.err.find("use --order 2"), std::string::npos) << linear.err;
  EXPECT_EQ(std::count(linear.err.begin(), linear.err.end(), '\n'), 1) << linear.err;
  EXPECT_GT(nlohmann::json::parse(linear.out)["frequency_error_estimates"][0].get<double>(), 0.05);
  EXPECT_TRUE(nlohmann::json::parse(linear.out)["mesh_refinement"].is_null());
  for (const char* key : {"nodes", "elements", "dofs", "mass_kg", "center_of_mass_m", "inertia_kgm2", "frequencies_hz",
                          "max_relative_residual", "mesh_quality", "timings_s", "peak_memory_mb", "output"})
    EXPECT_TRUE(json.contains(key)) << key;
  EXPECT_EQ(json["length_unit"], "mm");
  EXPECT_EQ(json["frequencies_hz"].size(), 6u);
  EXPECT_LT(json["max_relative_residual"].get<double>(), 1e-10);  // a compact part: far below 1e-8
  // Each mode's residual against its rounding floor (eigen_residual.hpp): 0.75 of it measured (converged modes in
  // general: up to 8.6; accepted up to 20).
  ASSERT_EQ(json["residual_floors"].size(), 6u);
  EXPECT_LT(json["max_residual_to_floor"].get<double>(), 5.0);
  EXPECT_GT(json["max_residual_to_floor"].get<double>(), 0.0);
  EXPECT_EQ(json["dofs"].get<long>(), 3 * json["nodes"].get<long>());
  // Mass = rho x meshed volume exactly; the meshed volume is within 1 % of the CAD volume (the curved quadratic
  // faces follow the bores and the fillet closely; the volume check holds 0.5 %): 90x40x8 + 8x40x52 + fillet 10x10x40 (1 - pi/4) - 3 bores, mm^3.
  const double cad_volume_mm3 = 90 * 40 * 8 + 8 * 40 * 52 + 100 * 40 * (1 - std::numbers::pi / 4) -
                                std::numbers::pi * (25 * 8 + 25 * 8 + 36 * 8);
  EXPECT_NEAR(json["mass_kg"].get<double>(), 7850 * json["mesh_quality"]["volume_m3"].get<double>(), 1e-9);
  EXPECT_NEAR(json["mesh_quality"]["volume_m3"].get<double>(), cad_volume_mm3 * 1e-9, 0.01 * cad_volume_mm3 * 1e-9);

  const auto body = flexbody::format::read_body_file(dir / "bracket.fbh5");
  EXPECT_EQ(body.mesh.nodes.rows(), json["nodes"].get<long>());
  EXPECT_EQ(body.modes.upsilon.cols(), 3 * 6);
  for (int k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(body.modes.frequencies_hz(k), json["frequencies_hz"][k].get<double>());
  // Body frame: origin at the centre of mass, which the file records in the input frame.
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(body.mass.center_of_mass_input(c), json["center_of_mass_m"][c].get<double>(), 1e-15);
  // The bracket's corner (0, 0, 0) mm is a node; in the body frame it sits at minus the centre of mass.
  const Eigen::RowVector3d corner = -body.mass.center_of_mass_input.transpose();
  EXPECT_LT((body.mesh.nodes.rowwise() - corner).rowwise().norm().minCoeff(), 1e-12);
  EXPECT_GT(body.mass.center_of_mass_input.norm(), 0.02);  // so the check above can fail
  EXPECT_EQ(body.provenance.source_file, "bracket.step");
  EXPECT_EQ(body.provenance.source_sha256.size(), 64u);

  // The GCMS constants: every field kept (the bracket has no degenerate pairs), G carries the mass.
  EXPECT_EQ(json["gcms_fields"].get<long>() + json["dropped_fields"].get<long>(), 3 * 6);
  EXPECT_EQ(body.gcms.field_count(), json["gcms_fields"].get<long>());
  EXPECT_NEAR(body.gcms.mass_matrix(0, 0), json["mass_kg"].get<double>(), 1e-12 * json["mass_kg"].get<double>());
  EXPECT_EQ(body.gcms.stiffness.rows(), 3 * body.gcms.field_count());
  EXPECT_EQ(json["dropped_fields"].get<long>(), 0);
  ASSERT_TRUE(json["condition_G_after"].is_number());  // null would mean singular
  EXPECT_GE(json["condition_G_after"].get<double>(), 1.0);
}

// Issue 13: after a failed load of some damaged files, HDF5's cleanup at exit printed "HDF5: infinite loop closing
// library" and a line of 'FL,FL,...' after the one error line (2,238 of 10,500 mutated files). This version-3 body
// file (a rigid cylinder's, with four flipped bytes; tests/data/damaged) is one of them: stderr must hold the one line.
// Readers refuse it unsealed now; `fbprep seal`, which converts version-3 files, still passes it to HDF5.
TEST(FbprepCli, ADamagedFileGivesOneLineAndNothingAtExit) {
  const auto dir = flexbody::test::scratch_dir();
  const auto damaged = std::filesystem::path(FLEXBODY_TEST_DATA_DIR) / "damaged" / "options-bit-flips-v3.fbh5";
  const CliRun run = fbprep(dir, fmt::format("seal '{}' -o converted.fbh5", damaged.string()));
  EXPECT_EQ(run.exit_code, 1);  // a body file that does not read, as for every fbprep error
  // The reader's walk over every link finds the damage first.
  EXPECT_EQ(run.err, fmt::format("fbprep: error: {}: its groups cannot be listed; it may be damaged (HDF5: incorrect "
                                 "metadata checksum after all read attempts)\n",
                                 damaged.string()));
  EXPECT_FALSE(std::filesystem::exists(dir / "converted.fbh5"));
}

TEST(FbprepCli, InspectReadsBackWhatWasWritten) {
  const auto dir = flexbody::test::scratch_dir();
  const CliRun prep = fbprep(dir, fmt::format("'{}' -o b.fbh5 --modes 3 --mesh-size 6 --volume-tolerance 0.01 --json", bracket_step().string()));
  ASSERT_EQ(prep.exit_code, 0) << prep.err;
  const auto written = nlohmann::json::parse(prep.out);

  const CliRun json_run = fbprep(dir, "inspect b.fbh5 --json");
  ASSERT_EQ(json_run.exit_code, 0) << json_run.err;
  const auto read = nlohmann::json::parse(json_run.out);
  EXPECT_EQ(read["format_version"], 4);
  EXPECT_EQ(read["sealed"], true);
  EXPECT_EQ(read["frequencies_hz"], written["frequencies_hz"]);  // the same doubles, through HDF5
  EXPECT_EQ(read["nodes"], written["nodes"]);
  EXPECT_EQ(read["gcms_fields"], written["gcms_fields"]);
  EXPECT_EQ(read["source_file"], "bracket.step");
  EXPECT_EQ(read["options"]["modes"], "3");
  // K̂'s spectrum holds the 3 modes (exactly, they are in the span of the fields) and more: its lowest
  // value is the first mode at most, its highest above the third.
  const auto range = read["k_hat_frequency_range_hz"];
  EXPECT_LE(range[0].get<double>(), written["frequencies_hz"][0].get<double>() * (1 + 1e-8));
  EXPECT_GT(range[1].get<double>(), written["frequencies_hz"][2].get<double>());

  const CliRun report = fbprep(dir, "inspect b.fbh5");
  ASSERT_EQ(report.exit_code, 0) << report.err;
  EXPECT_NE(report.out.find("flexbody body file, format version 4, sealed"), std::string::npos) << report.out;
  EXPECT_NE(report.out.find("GCMS constants"), std::string::npos) << report.out;

  write(dir / "input-broken.fbh5", "not an HDF5 file at all");
  const CliRun broken = fbprep(dir, "inspect input-broken.fbh5");
  EXPECT_EQ(broken.exit_code, 1);
  EXPECT_EQ(broken.err, "fbprep: error: input-broken.fbh5: not an HDF5 file\n");
  const CliRun usage = fbprep(dir, "inspect b.fbh5 --frobnicate");
  EXPECT_EQ(usage.exit_code, 2);
  EXPECT_EQ(std::count(usage.err.begin(), usage.err.end(), '\n'), 1) << usage.err;
}


TEST(FbprepCli, ExportVtuWritesTheModesForParaView) {
  const auto dir = flexbody::test::scratch_dir();
  // Linear tetrahedra: the export of quadratic ones is tested below (QuadraticTetrahedraEndToEnd).
  const CliRun prep = fbprep(dir, fmt::format("'{}' -o b.fbh5 --modes 3 --order 1 --mesh-size 6 --volume-tolerance 0.01 --json", bracket_step().string()));
  ASSERT_EQ(prep.exit_code, 0) << prep.err;
  const CliRun run = fbprep(dir, "export-vtu b.fbh5 -o paraview");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out, "paraview/b.vtu\n");
  const std::string vtu = slurp(dir / "paraview" / "b.vtu");
  const auto body = flexbody::format::read_body_file(dir / "b.fbh5");
  EXPECT_NE(vtu.find(fmt::format("NumberOfPoints=\"{}\" NumberOfCells=\"{}\"", body.mesh.nodes.rows(),
                                 body.mesh.tets.rows())), std::string::npos);
  for (int m = 0; m < 3; ++m) {
    const std::string name = fmt::format("mode_{:02d}_{:.6g}Hz", m + 1, body.modes.frequencies_hz(m));
    const std::vector<unsigned char> bytes = base64_decode(vtu_array(vtu, name));
    ASSERT_EQ(bytes.size(), 8 + 3 * 8 * static_cast<std::size_t>(body.mesh.nodes.rows())) << name;
    std::vector<double> values(3 * body.mesh.nodes.rows());
    std::memcpy(values.data(), bytes.data() + 8, values.size() * 8);
    double worst = 0.0;
    for (Eigen::Index i = 0; i < body.mesh.nodes.rows(); ++i)
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(values[3 * i + k] - body.modes.upsilon(i, 3 * m + k)));
    EXPECT_EQ(worst, 0.0) << name;  // the same doubles, bit for bit
  }
  // Mode 2's stress tensor and von Mises stress: nodal_stresses of the modes (all three at once, as the export
  // computes them: same call, same bits), reordered to ParaView's XX, YY, ZZ, XY, YZ, XZ.
  {
    const Eigen::Index n = body.mesh.nodes.rows();
    Eigen::MatrixXd displacements(3 * n, 3);
    for (Eigen::Index i = 0; i < n; ++i)
      for (int m = 0; m < 3; ++m) displacements.col(m).segment<3>(3 * i) = body.modes.upsilon.block<1, 3>(i, 3 * m).transpose();
    const Eigen::MatrixXd stresses = flexbody::preprocess::nodal_stresses(flexbody::preprocess::TetMesh{body.mesh.nodes, body.mesh.tets}, body.material,
                                                                          displacements);
    const std::string name = fmt::format("stress_02_{:.6g}Hz", body.modes.frequencies_hz(1));
    const std::vector<unsigned char> bytes = base64_decode(vtu_array(vtu, name));
    ASSERT_EQ(bytes.size(), 8 + 6 * 8 * static_cast<std::size_t>(n)) << name;
    EXPECT_NE(vtu.find("Name=\"" + name + "\" NumberOfComponents=\"6\""), std::string::npos);
    std::vector<double> values(6 * n);
    std::memcpy(values.data(), bytes.data() + 8, values.size() * 8);
    const std::vector<unsigned char> mises_bytes = base64_decode(vtu_array(vtu, "mises_02"));
    ASSERT_EQ(mises_bytes.size(), 8 + 8 * static_cast<std::size_t>(n));
    std::vector<double> mises(n);
    std::memcpy(mises.data(), mises_bytes.data() + 8, mises.size() * 8);
    const int voigt_of_paraview[6] = {0, 1, 2, 3, 5, 4};  // ours: xx yy zz xy xz yz
    double worst = 0.0, worst_mises = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Matrix<double, 6, 1> s = stresses.col(1).segment<6>(6 * i);
      for (int k = 0; k < 6; ++k) worst = std::max(worst, std::abs(values[6 * i + k] - s(voigt_of_paraview[k])));
      worst_mises = std::max(worst_mises, std::abs(mises[i] - flexbody::preprocess::von_mises(s)));
    }
    EXPECT_EQ(worst, 0.0) << name;
    EXPECT_EQ(worst_mises, 0.0);
    EXPECT_GT(stresses.col(1).cwiseAbs().maxCoeff(), 0.0);  // an elastic mode stresses the part
  }
  EXPECT_NE(vtu_array(vtu, fmt::format("field_{:03d}", body.gcms.field_count())), "");
  EXPECT_NE(vtu_array(vtu, "interface"), "");
  EXPECT_EQ(fbprep(dir, "export-vtu absent.fbh5 -o paraview").exit_code, 1);
}

// --order 2 end to end through the command line (issue 15): the report's --json gives the element order and counts
// the mid-edge nodes in nodes and DOFs; inspect reads the order back; export-vtu writes VTK quadratic tetrahedra (cell
// type 24, 10 points each, the body file's node order) so ParaView draws the curved faces.
TEST(FbprepCli, QuadraticTetrahedraEndToEnd) {
  const auto dir = flexbody::test::scratch_dir();
  const CliRun prep = fbprep(dir, fmt::format("'{}' -o q.fbh5 --order 2 --modes 3 --mesh-size 8 --json",
                                              bracket_step().string()));
  ASSERT_EQ(prep.exit_code, 0) << prep.err;
  const auto summary = nlohmann::json::parse(prep.out);
  EXPECT_EQ(summary["element_order"], 2);
  EXPECT_EQ(summary["dofs"].get<long>(), 3 * summary["nodes"].get<long>());
  EXPECT_GT(summary["nodes"].get<long>(), 4 * summary["elements"].get<long>() / 3);  // corners alone: ~n_e / 5
  const double jacobian = summary["mesh_quality"]["min_jacobian_ratio"];
  EXPECT_GT(jacobian, 0.0);
  EXPECT_LE(jacobian, 1.0);
  const auto body = flexbody::format::read_body_file(dir / "q.fbh5");
  EXPECT_EQ(body.mesh.element_order, 2);
  EXPECT_EQ(body.mesh.nodes.rows(), summary["nodes"].get<long>());
  const CliRun inspect = fbprep(dir, "inspect q.fbh5 --json");
  ASSERT_EQ(inspect.exit_code, 0) << inspect.err;
  EXPECT_EQ(nlohmann::json::parse(inspect.out)["element_order"], 2);
  EXPECT_EQ(nlohmann::json::parse(inspect.out)["dofs"].get<long>(), 3 * body.mesh.nodes.rows());
  const CliRun vtu_run = fbprep(dir, "export-vtu q.fbh5 -o paraview");
  ASSERT_EQ(vtu_run.exit_code, 0) << vtu_run.err;
  const std::string vtu = slurp(dir / "paraview" / "q.vtu");
  const std::vector<unsigned char> types = base64_decode(vtu_array(vtu, "types"));
  ASSERT_EQ(types.size(), 8 + static_cast<std::size_t>(body.mesh.tets.rows()));
  EXPECT_TRUE(std::all_of(types.begin() + 8, types.end(), [](unsigned char t) { return t == 24; }));
  const std::vector<std::int64_t> connectivity = flexbody::test::vtu_values<std::int64_t>(vtu, "connectivity");
  ASSERT_EQ(connectivity.size(), static_cast<std::size_t>(body.mesh.tets.size()));
  EXPECT_TRUE(std::equal(connectivity.begin(), connectivity.end(), body.mesh.tets.data()));
}

// --mesher hxt meshes with gmsh's parallel HXT algorithm (issue 16): the report and the body file say so, and the
// beam's first bending pair with quadratic elements is as close to Timoshenko as the default mesher's (0.2 %; both
// measured within 0.07 %). An unknown algorithm is a bad command line.
TEST(FbprepCli, MesherHxt) {
  const auto dir = flexbody::test::scratch_dir();
  const std::string beam =
      fmt::format("'{}'", (std::filesystem::path(FLEXBODY_TEST_DATA_DIR) / "gmsh-beam" / "beam_1m.geo").string());
  expect_refusal(dir, beam + " --unit m --mesher tetgen", "--mesher 'tetgen' is not one of delaunay, hxt");
  const CliRun run = fbprep(dir, beam + " --unit m --mesh-size 0.05 --order 2 --modes 2 --mesher hxt -o h.fbh5 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["mesher"], "hxt");
  const double pair = 0.5 * (json["frequencies_hz"][0].get<double>() + json["frequencies_hz"][1].get<double>());
  EXPECT_LT(std::abs(pair / 263.46 - 1.0), 2e-3);
  bool recorded = false;
  for (const auto& [name, value] : flexbody::format::read_body_file(dir / "h.fbh5").provenance.options)
    recorded = recorded || (name == "mesher" && value == "hxt");
  EXPECT_TRUE(recorded);
}

TEST(FbprepCli, BundledBracketSpecPutsMarkersOnTheBoreAxes) {
  // meshes/bracket.yaml (the quick start's spec), coarser and with fewer modes to stay quick.
  const auto dir = flexbody::test::scratch_dir();
  const auto spec = std::filesystem::path(FLEXBODY_SOURCE_DIR) / "meshes" / "bracket.yaml";
  const CliRun run = fbprep(dir, fmt::format("'{}' -o b.fbh5 --mesh-size 6 --volume-tolerance 0.01 --modes 2 --json", spec.string()));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto body = flexbody::format::read_body_file(dir / "b.fbh5");
  ASSERT_EQ(body.interfaces.size(), 3u);
  // Area centroids of the faceted bores: on the axis (the facets are symmetric to ~1e-5 m at 6 mm) and
  // mid-way through the 8 mm wall.
  const Eigen::Vector3d expected[3] = {{0.045, 0.020, 0.004}, {0.075, 0.020, 0.004}, {0.004, 0.020, 0.042}};
  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE(body.interfaces[k].name);
    EXPECT_LT((body.interfaces[k].reference_point + body.mass.center_of_mass_input - expected[k]).norm(), 5e-5);
  }
}

TEST(FbprepCli, ListSurfacesFindsTheBores) {
  const auto dir = flexbody::test::scratch_dir();
  // Bore 1: radius 5 mm through the 8 mm plate at (45, 20) mm. Its faceted area is below the cylinder's 2 pi r h by
  // the chord error, (h/r)^2 / 24 ~ 1.5 % at a 3 mm mesh on a 5 mm radius. With --order 2 the surfaces are those
  // fbprep --order 2 selects from: each 6-node triangle as four, its mid-edge nodes on the bore, so the chords are half
  // as long and the faceted area's shortfall a quarter, ~0.4 %.
  for (const auto& [order, smallest] : {std::pair{1, 0.97}, std::pair{2, 0.99}}) {
    SCOPED_TRACE(order);
    const CliRun run = fbprep(dir, fmt::format("list-surfaces '{}' --mesh-size 3 --order {} --json",
                                               bracket_step().string(), order));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto json = nlohmann::json::parse(run.out);
    int bores = 0;
    for (const auto& s : json["surfaces"]) {
      const Eigen::Vector3d c(s["centroid_m"][0].get<double>(), s["centroid_m"][1].get<double>(),
                              s["centroid_m"][2].get<double>());
      if ((c - Eigen::Vector3d(0.045, 0.020, 0.004)).norm() > 1e-4) continue;
      ++bores;
      const double cylinder = 2 * std::numbers::pi * 0.005 * 0.008;
      EXPECT_LT(s["area_m2"].get<double>(), cylinder);
      EXPECT_GT(s["area_m2"].get<double>(), smallest * cylinder);
    }
    EXPECT_EQ(bores, 1);
  }
  EXPECT_EQ(fbprep(dir, "list-surfaces absent.step").exit_code, 1);
}

TEST(FbprepCli, GeoInMillimetresGivesTheSameBodyAsTheStep) {
  const auto dir = flexbody::test::scratch_dir();
  const auto geo = std::filesystem::path(FLEXBODY_SOURCE_DIR) / "meshes" / "bracket.geo";
  const CliRun step = fbprep(dir, fmt::format("'{}' -o a.fbh5 --modes 1 --mesh-size 6 --volume-tolerance 0.01 --json", bracket_step().string()));
  const CliRun mm = fbprep(dir, fmt::format("'{}' -o b.fbh5 --modes 1 --mesh-size 6 --volume-tolerance 0.01 --unit mm --json", geo.string()));
  const CliRun m = fbprep(dir, fmt::format("'{}' -o c.fbh5 --modes 1 --mesh-size 6 --volume-tolerance 0.01 --unit m --json", geo.string()));
  ASSERT_EQ(step.exit_code, 0) << step.err;
  ASSERT_EQ(mm.exit_code, 0) << mm.err;
  ASSERT_EQ(m.exit_code, 0) << m.err;
  const auto a = nlohmann::json::parse(step.out), b = nlohmann::json::parse(mm.out), c = nlohmann::json::parse(m.out);
  // Same geometry and element size: nearly the same mesh (measured: 1806 and 1805 tetrahedra, 3771 and 3770 nodes
  // with quadratic ones; the two files give gmsh the same curves in different parametrisations). The STEP file
  // stores the geometry through OpenCASCADE's tolerances (1e-7 mm), so the masses agree to ~1e-7, not to round-off.
  EXPECT_NEAR(a["nodes"].get<double>(), b["nodes"].get<double>(), 1e-3 * b["nodes"].get<double>());
  EXPECT_NEAR(a["mass_kg"].get<double>(), b["mass_kg"].get<double>(), 1e-6 * b["mass_kg"].get<double>());
  // Read as metres (with the same numbers), the bracket is 1000 times larger: 1e9 times the mass, 1/1000 the frequency.
  EXPECT_NEAR(c["mass_kg"].get<double>() / b["mass_kg"].get<double>(), 1e9, 1e-3);
  EXPECT_NEAR(b["frequencies_hz"][0].get<double>() / c["frequencies_hz"][0].get<double>(), 1e3, 1e-6);
  EXPECT_EQ(b["length_unit"], "mm");

  // BREP (no unit in the file) of the same geometry, read in mm. Its serialized surfaces mesh a little
  // differently (measured: 659 against 657 nodes), so the faceted bores differ: masses within 1e-4
  // (measured 7e-6).
  const CliRun brep = fbprep(dir, fmt::format("'{}' -o d.fbh5 --modes 1 --mesh-size 6 --volume-tolerance 0.01 --unit mm --json",
                                              (geo.parent_path() / "bracket.brep").string()));
  ASSERT_EQ(brep.exit_code, 0) << brep.err;
  const auto d = nlohmann::json::parse(brep.out);
  EXPECT_EQ(d["input_format"], "BREP");
  EXPECT_NEAR(d["nodes"].get<double>(), b["nodes"].get<double>(), 0.02 * b["nodes"].get<double>());
  EXPECT_NEAR(d["mass_kg"].get<double>(), b["mass_kg"].get<double>(), 1e-4 * b["mass_kg"].get<double>());
}

TEST(FbprepCli, FmaxKeepsExactlyTheModesBelowIt) {
  const auto dir = flexbody::test::scratch_dir();
  const CliRun four = fbprep(dir, fmt::format("'{}' -o a.fbh5 --modes 4 --mesh-size 6 --volume-tolerance 0.01 --json", bracket_step().string()));
  ASSERT_EQ(four.exit_code, 0) << four.err;
  const auto f = nlohmann::json::parse(four.out)["frequencies_hz"];
  const double fmax = 0.5 * (f[1].get<double>() + f[2].get<double>());  // between the 2nd and 3rd mode
  const CliRun below = fbprep(dir, fmt::format("'{}' -o b.fbh5 --fmax {:.9g} --mesh-size 6 --volume-tolerance 0.01 --json",
                                               bracket_step().string(), fmax));
  ASSERT_EQ(below.exit_code, 0) << below.err;
  const auto g = nlohmann::json::parse(below.out)["frequencies_hz"];
  ASSERT_EQ(g.size(), 2u);
  EXPECT_NEAR(g[1].get<double>(), f[1].get<double>(), 1e-9 * f[1].get<double>());
  const CliRun none = fbprep(dir, fmt::format("'{}' -o c.fbh5 --fmax 10 --mesh-size 6 --volume-tolerance 0.01", bracket_step().string()));
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_NE(none.err.find("no elastic mode at or below fmax = 10 Hz"), std::string::npos) << none.err;
}

TEST(FbprepCli, RefusesBadInputsWithOneLine) {
  const auto dir = flexbody::test::scratch_dir();
  expect_refusal(dir, "nothing-here.step", "nothing-here.step: no such file");
  write(dir / "input-garbage.step", "this is not a STEP file\n");
  expect_refusal(dir, "input-garbage.step", "input-garbage.step: Could not read file");
  write(dir / "input-sheet.geo", std::string(kOcc) + "Rectangle(1) = {0, 0, 0, 1, 1};\n");
  expect_refusal(dir, "input-sheet.geo --unit m", "input-sheet.geo: the input has no volume (1 surfaces)");
  write(dir / "input-two.geo", std::string(kOcc) + "Box(1) = {0, 0, 0, 1, 1, 1};\nBox(2) = {3, 0, 0, 1, 1, 1};\n");
  expect_refusal(dir, "input-two.geo --unit m", "input-two.geo: found 2 disconnected solids; an assembly is not one body");
  expect_refusal(dir, "input-two.geo", "gmsh .geo files carry no length unit; pass --unit");
  write(dir / "input-inverted.msh",
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n"
        "$Elements\n2\n1 4 2 1 1 1 2 3 4\n2 4 2 1 1 2 4 3 5\n$EndElements\n");
  expect_refusal(dir, "input-inverted.msh --unit m",
                 "input-inverted.msh: 1 inverted or zero-volume element, first is tetrahedron 1");
  write(dir / "input-cube.geo", std::string(kOcc) + "Box(1) = {0, 0, 0, 1, 1, 1};\n");
  expect_refusal(dir, "input-cube.geo --unit m --material E=-1,nu=0.3,rho=7850", "E must be positive, got -1");
  expect_refusal(dir, "input-cube.geo --unit m --material E=1e9,nu=0.3,rho=0", "rho must be positive, got 0");
  expect_refusal(dir, "input-cube.geo --unit m --material E=1e9,nu=0.5,rho=1000", "nu must lie in (-1, 0.5), got 0.5");
  expect_refusal(dir, "input-cube.geo --unit m --material E=1e9,nu=-1.2,rho=1000", "nu must lie in (-1, 0.5), got -1.2");
  expect_refusal(dir, "input-cube.geo --unit m --material unobtainium", "'unobtainium' is unknown");
  expect_refusal(dir, "input-cube.geo --unit m --material E=nan,nu=0.3,rho=1", "E must be positive, got nan");
  expect_refusal(dir, "input-cube.geo --unit m --material E=1e9,E=2e9,nu=0.3,rho=1", "E is given twice");
  expect_refusal(dir, "input-cube.geo --unit m --material E=1e9,nu=0.3", "rho is missing");
  expect_refusal(dir, "input-cube.geo --unit furlong", "--unit 'furlong' is not one of mm, cm, m, in");
  expect_refusal(dir, "input-cube.geo --unit m --eigensolver lapack", "'lapack' is unknown; use auto, arpack, spectra, block-lanczos or slepc");
  if (!flexbody::preprocess::slepc_available())  // a build without the backend says how to get it
    expect_refusal(dir, "input-cube.geo --unit m --eigensolver slepc",
                   "eigensolver: 'slepc' is not in this build (configure with -DFLEXBODY_WITH_SLEPC=ON)");
  expect_refusal(dir, "input-cube.geo --unit m --order 3", "--order 3: the element order is 1 (linear tetrahedra) or 2");
  expect_refusal(dir, "input-cube.txt --unit m", "unsupported file type '.txt'");
  expect_refusal(dir, "input-cube.geo --unit m --modes 100000", "--modes 100000: at most");
  // A bracket in mm read as metres with a size meant in mm: a unit mistake, refused before meshing.
  const auto geo = std::filesystem::path(FLEXBODY_SOURCE_DIR) / "meshes" / "bracket.geo";
  expect_refusal(dir, fmt::format("'{}' --unit m --mesh-size 0.006", geo.string()),
                 "element size 0.006 m would give about 1.7e+12 tetrahedra");
}

TEST(FbprepCli, FailedRunLeavesAnExistingTargetUntouched) {
  const auto dir = flexbody::test::scratch_dir();
  write(dir / "input-sheet.geo", std::string(kOcc) + "Rectangle(1) = {0, 0, 0, 1, 1};\n");
  // It begins like a body file (HDF5's signature), so fbprep would replace it; the run fails before it does.
  const std::string previous = std::string("\x89HDF\r\n\x1a\n", 8) + "previous contents";
  write(dir / "input-old.fbh5", previous);
  const CliRun run = fbprep(dir, "input-sheet.geo --unit m -o input-old.fbh5");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("input-sheet.geo: the input has no volume"), std::string::npos) << run.err;
  EXPECT_EQ(slurp(dir / "input-old.fbh5"), previous);
  expect_no_output(dir);
}

TEST(FbprepCli, BadOptionValuesExitWith2AndFailuresWith1) {
  const auto dir = flexbody::test::scratch_dir();
  write(dir / "input-cube.geo", std::string(kOcc) + "Box(1) = {0, 0, 0, 1, 1, 1};\n");
  for (const char* options : {"--unit furlong", "--unit m --material steel2", "--unit m --eigensolver lapack",
                              "--unit m --order 3", "--unit m --modes -1", "--unit m --bogus",
                              "--unit m --volume-tolerance 0", "--unit m --volume-tolerance 1"}) {
    SCOPED_TRACE(options);
    EXPECT_EQ(fbprep(dir, fmt::format("input-cube.geo {} -o out.fbh5", options)).exit_code, 2);
  }
  EXPECT_EQ(fbprep(dir, "input-missing.geo --unit m -o out.fbh5").exit_code, 1);
  // The output may not overwrite the input.
  const CliRun same = fbprep(dir, "input-cube.geo --unit m -o input-cube.geo");
  EXPECT_EQ(same.exit_code, 2);
  EXPECT_NE(same.err.find("the output would overwrite the input"), std::string::npos) << same.err;
  expect_no_output(dir);
}

TEST(FbprepCli, StepDeclaredInInchesIsReadInInches) {
  // The bracket's STEP file with its length unit changed from mm to inch (the form CAD systems write:
  // a conversion-based unit pointing at an SI unit): OpenCASCADE scales the geometry by 25.4, and
  // fbprep must say inches, not the mm of the SI unit the inch refers to.
  const auto dir = flexbody::test::scratch_dir();
  std::string step = slurp(bracket_step());
  const std::string mm_unit = "( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );";
  const auto at = step.find(mm_unit);
  ASSERT_NE(at, std::string::npos);
  step.replace(at, mm_unit.size(),
               "( CONVERSION_BASED_UNIT('INCH',#9000) LENGTH_UNIT() NAMED_UNIT(#9001) );\n"
               "#9000 = LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#9002);\n"
               "#9001 = DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.);\n"
               "#9002 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );");
  write(dir / "input-inch.step", step);
  // The geometry is 25.4 times larger; an element size of 6 (in the declared unit) gives the same mesh.
  const CliRun mm = fbprep(dir, fmt::format("'{}' -o a.fbh5 --modes 1 --mesh-size 6 --volume-tolerance 0.01 --json", bracket_step().string()));
  const CliRun inch = fbprep(dir, fmt::format("input-inch.step -o b.fbh5 --modes 1 --mesh-size 6 --volume-tolerance 0.01 --json"));
  ASSERT_EQ(mm.exit_code, 0) << mm.err;
  ASSERT_EQ(inch.exit_code, 0) << inch.err;
  const auto a = nlohmann::json::parse(mm.out), b = nlohmann::json::parse(inch.out);
  EXPECT_EQ(b["length_unit"], "in");
  EXPECT_EQ(a["nodes"], b["nodes"]);
  // Same node count, but gmsh's placement tolerances scale with the model: measured 2.5e-4 apart.
  EXPECT_NEAR(b["mass_kg"].get<double>() / a["mass_kg"].get<double>(), std::pow(25.4, 3), 1e-3 * std::pow(25.4, 3));
}

TEST(FbprepCli, ExplicitUnitOverridesTheStepDeclaration) {
  // Issue 12: an explicit unit is the unit of the file's numbers and wins over the STEP declaration, and
  // the report, --json and the body file say what the file declares and that --unit overrode it.
  const auto dir = flexbody::test::scratch_dir();
  // The bracket declares mm; read as metres it is the same mesh (the element size is in the unit in force,
  // 6 both ways), 1000 times larger: K x 1000, M x 1e9, frequencies / 1000 (to the eigen solve's 1e-10
  // relative residual, which enters the eigenvalue squared).
  const std::string bracket = bracket_step().string();
  const CliRun as_declared = fbprep(dir, fmt::format("'{}' -o a.fbh5 --modes 1 --mesh-size 6 --volume-tolerance 0.01 --json", bracket));
  const CliRun metres = fbprep(dir, fmt::format("'{}' -o b.fbh5 --modes 1 --mesh-size 6 --volume-tolerance 0.01 --unit m --json", bracket));
  ASSERT_EQ(as_declared.exit_code, 0) << as_declared.err;
  ASSERT_EQ(metres.exit_code, 0) << metres.err;
  // A 90 m part is no unit mistake: no size warning (only the coarse mesh's accuracy warning).
  EXPECT_EQ(metres.err.find("across"), std::string::npos) << metres.err;
  const auto a = nlohmann::json::parse(as_declared.out), b = nlohmann::json::parse(metres.out);
  EXPECT_EQ(a["length_unit"], "mm");
  EXPECT_EQ(a["declared_unit"], "mm");
  EXPECT_EQ(a["unit_overrides_declared"], false);
  EXPECT_EQ(b["length_unit"], "m");
  EXPECT_EQ(b["declared_unit"], "mm");
  EXPECT_EQ(b["unit_overrides_declared"], true);
  const std::string override_reason = "the STEP file declares mm; --unit m overrides it: coordinates read as metres";
  EXPECT_EQ(b["length_unit_reason"], override_reason);
  EXPECT_EQ(a["nodes"], b["nodes"]);
  EXPECT_NEAR(b["mesh_size_m"].get<double>() / a["mesh_size_m"].get<double>(), 1e3, 1e-9);
  EXPECT_NEAR(b["mass_kg"].get<double>() / a["mass_kg"].get<double>(), 1e9, 1e-9 * 1e9);
  EXPECT_NEAR(b["frequencies_hz"][0].get<double>() / a["frequencies_hz"][0].get<double>(), 1e-3, 1e-11);
  const auto body = flexbody::format::read_body_file(dir / "b.fbh5");
  EXPECT_EQ(body.provenance.input_unit, "m");
  EXPECT_EQ(body.provenance.declared_unit, "mm");
  EXPECT_EQ(body.provenance.unit_reason, override_reason);
  EXPECT_EQ(flexbody::format::read_body_file(dir / "a.fbh5").provenance.declared_unit, "mm");
  const CliRun inspect = fbprep(dir, "inspect b.fbh5 --json");
  ASSERT_EQ(inspect.exit_code, 0) << inspect.err;
  const auto read = nlohmann::json::parse(inspect.out);
  EXPECT_EQ(read["declared_unit"], "mm");
  EXPECT_EQ(read["unit_reason"], override_reason);

  // The issue's own case: gmsh's STEP writer declares mm whatever the numbers mean; this beam's are
  // metres. A box's tetrahedra fill it exactly: mass = 7850 kg/m^3 x 1 x 0.05^2 m^3 to rounding. Its first
  // free-free bending mode: Timoshenko 263.46 Hz, stiffer on this coarse mesh (evidence: +42 % at 1k DOFs).
  const CliRun beam = fbprep(dir, fmt::format("'{}' -o c.fbh5 --modes 1 --mesh-size 0.025 --unit m",
                                              gmsh_beam_step().string()));
  ASSERT_EQ(beam.exit_code, 0) << beam.err;
  EXPECT_NE(beam.out.find("length unit"), std::string::npos) << beam.out;
  EXPECT_NE(beam.out.find(" m: " + override_reason + "\n"), std::string::npos) << beam.out;
  const auto c = flexbody::format::read_body_file(dir / "c.fbh5");
  EXPECT_NEAR(c.mass.mass, 19.625, 1e-9 * 19.625);
  EXPECT_LT((c.mass.center_of_mass_input - Eigen::Vector3d(0.5, 0.025, 0.025)).norm(), 1e-12);
  EXPECT_GT(c.modes.frequencies_hz(0), 263.46);
  EXPECT_LT(c.modes.frequencies_hz(0), 1.6 * 263.46);

  // An explicit unit equal to the declared one is no override; list-surfaces follows the same rule.
  const std::string beam_step = gmsh_beam_step().string();
  const CliRun same = fbprep(dir, fmt::format("list-surfaces '{}' --unit mm --mesh-size 0.025 --json", beam_step));
  ASSERT_EQ(same.exit_code, 0) << same.err;
  EXPECT_EQ(nlohmann::json::parse(same.out)["length_unit_reason"], "declared in the STEP file (mm); --unit mm agrees");
  const CliRun faces = fbprep(dir, fmt::format("list-surfaces '{}' --unit m --mesh-size 0.025 --json", beam_step));
  ASSERT_EQ(faces.exit_code, 0) << faces.err;
  const auto listed = nlohmann::json::parse(faces.out);
  EXPECT_EQ(listed["length_unit"], "m");
  EXPECT_EQ(listed["declared_unit"], "mm");
  int tips = 0;  // the end face x = 1 m, 0.05 x 0.05 m
  for (const auto& surface : listed["surfaces"])
    if (std::abs(surface["centroid_m"][0].get<double>() - 1.0) < 1e-12) {
      ++tips;
      EXPECT_NEAR(surface["area_m2"].get<double>(), 0.0025, 1e-15);
    }
  EXPECT_EQ(tips, 1);
}

TEST(FbprepCli, StepWithoutDeclaredUnitTakesTheExplicitOne) {
  // A STEP file with no LENGTH_UNIT: OpenCASCADE takes its numbers as mm (measured: the box's bounding box
  // is 1 x 0.05 x 0.05 after import); --unit says what they are.
  const auto dir = flexbody::test::scratch_dir();
  std::string step = slurp(gmsh_beam_step());
  const std::string mm_unit = "( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );";
  const auto at = step.find(mm_unit);
  ASSERT_NE(at, std::string::npos);
  step.replace(at, mm_unit.size(), "( NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );");
  write(dir / "input-unitless.step", step);
  const CliRun plain = fbprep(dir, "list-surfaces input-unitless.step --mesh-size 0.025 --json");
  const CliRun metres = fbprep(dir, "list-surfaces input-unitless.step --unit m --mesh-size 0.025 --json");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  ASSERT_EQ(metres.exit_code, 0) << metres.err;
  const auto a = nlohmann::json::parse(plain.out), b = nlohmann::json::parse(metres.out);
  EXPECT_EQ(a["length_unit"], "mm");
  EXPECT_EQ(a["declared_unit"], nullptr);
  EXPECT_EQ(b["length_unit"], "m");
  EXPECT_EQ(b["declared_unit"], nullptr);
  EXPECT_EQ(b["length_unit_reason"], "the STEP file declares no length unit; --unit m: coordinates read as metres");
  double area_a = 0.0, area_b = 0.0;
  for (const auto& s : a["surfaces"]) area_a += s["area_m2"].get<double>();
  for (const auto& s : b["surfaces"]) area_b += s["area_m2"].get<double>();
  EXPECT_NEAR(area_b, 4 * 0.05 + 2 * 0.0025, 1e-12);  // the box's surface in m^2
  EXPECT_NEAR(area_b / area_a, 1e6, 1e-6);

  // A declaration that the writer wrapped over two lines is still read (and so can be overridden).
  step = slurp(gmsh_beam_step());
  step.replace(step.find(mm_unit), mm_unit.size(), "( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,\n.METRE.) );");
  write(dir / "input-wrapped.step", step);
  const CliRun wrapped = fbprep(dir, "list-surfaces input-wrapped.step --unit m --mesh-size 0.025 --json");
  ASSERT_EQ(wrapped.exit_code, 0) << wrapped.err;
  EXPECT_EQ(nlohmann::json::parse(wrapped.out)["declared_unit"], "mm");
}

TEST(FbprepCli, UnitThatCannotBeAppliedIsRefused) {
  // fbprep cannot undo a conversion whose factor it does not know: OpenCASCADE converts an IGES file's
  // unit (fbprep reads no IGES header) and STEP units other than mm, cm, m, inch to mm by itself.
  const auto dir = flexbody::test::scratch_dir();
  write(dir / "input-part.igs", "an IGES file\n");
  expect_refusal(dir, "input-part.igs --unit m",
                 "input-part.igs: fbprep does not read the unit an IGES file declares (OpenCASCADE converts it to "
                 "mm), so --unit m cannot be applied; drop it to read the file as it declares (lengths then in mm), "
                 "or export the part as STEP");
  EXPECT_EQ(fbprep(dir, "input-part.igs --unit mm -o out.fbh5").exit_code, 2);
  std::string step = slurp(gmsh_beam_step());
  const auto at = step.find("SI_UNIT(.MILLI.,.METRE.) );");
  ASSERT_NE(at, std::string::npos);
  step.replace(at, 15, "SI_UNIT(.MICRO.");
  write(dir / "input-micro.step", step);
  expect_refusal(dir, "input-micro.step --unit m",
                 "input-micro.step: the STEP file declares a length unit fbprep does not read (OpenCASCADE converts "
                 "it to mm), so --unit m cannot override it; drop it to read the file as it declares (lengths then "
                 "in mm)");
}

// Issue 13: `fbprep spec.yaml -o spec.yaml` replaced the spec with the body file (only the geometry was compared).
// No input, by any path to it (relative, a symbolic or a hard link), may be the output.
TEST(FbprepCli, OutputIsNeverAnInput) {
  const auto dir = flexbody::test::scratch_dir();
  write(dir / "input-cube.geo", std::string(kOcc) + "Box(1) = {0, 0, 0, 1, 1, 1};\n");
  const std::string spec = "input: input-cube.geo\nunit: m\nreduction: {modes: 2}\n";
  write(dir / "input-spec.yaml", spec);
  std::filesystem::create_directory(dir / "input-sub");
  std::filesystem::create_symlink("input-spec.yaml", dir / "input-spec-link.fbh5");
  std::filesystem::create_hard_link(dir / "input-spec.yaml", dir / "input-spec-hard.fbh5");
  std::filesystem::create_symlink("input-cube.geo", dir / "input-cube-link.fbh5");
  for (const auto& [arguments, message] : std::vector<std::pair<std::string, std::string>>{
           {"input-spec.yaml -o input-spec.yaml", "the output would overwrite the body spec input-spec.yaml"},
           {"input-spec.yaml -o ./input-sub/../input-spec.yaml", "the output would overwrite the body spec"},
           {"input-spec.yaml -o input-spec-link.fbh5", "the output would overwrite the body spec"},
           {"input-spec.yaml -o input-spec-hard.fbh5", "the output would overwrite the body spec"},
           {"input-spec.yaml -o input-cube-link.fbh5", "the output would overwrite the input"},
           {"input-cube.geo --unit m -o input-cube-link.fbh5", "the output would overwrite the input"}}) {
    SCOPED_TRACE(arguments);
    const CliRun run = fbprep(dir, arguments);
    EXPECT_EQ(run.exit_code, 2);
    EXPECT_EQ(run.out, "");
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
    EXPECT_EQ(run.err.rfind("fbprep: error: ", 0), 0u) << run.err;
    EXPECT_NE(run.err.find(message), std::string::npos) << run.err;
    EXPECT_EQ(slurp(dir / "input-spec.yaml"), spec);
    EXPECT_EQ(slurp(dir / "input-cube.geo"), std::string(kOcc) + "Box(1) = {0, 0, 0, 1, 1, 1};\n");
    EXPECT_TRUE(std::filesystem::is_symlink(dir / "input-spec-link.fbh5"));
    expect_no_output(dir);
  }
}

// Issue 13: --mesh-size 0 silently meshed at the default size and --modes 0 computed 10 modes (recording modes=10).
// A value given is used as given: zero, negative and non-finite ones are refused, naming the option or the spec line.
TEST(FbprepCli, NumericOptionsMustBePositive) {
  const auto dir = flexbody::test::scratch_dir();
  write(dir / "input-cube.geo", std::string(kOcc) + "Box(1) = {0, 0, 0, 1, 1, 1};\n");
  expect_refusal(dir, "input-cube.geo --unit m --mesh-size 0", "--mesh-size must be a positive number");
  expect_refusal(dir, "input-cube.geo --unit m --mesh-size -0.5", "--mesh-size must be a positive number");
  expect_refusal(dir, "input-cube.geo --unit m --modes 0", "--modes must be at least 1, got 0");
  expect_refusal(dir, "input-cube.geo --unit m --fmax 0", "--fmax must be a positive frequency in Hz, got 0");
  expect_refusal(dir, "input-cube.geo --unit m --fmax -5", "--fmax must be a positive frequency in Hz, got -5");
  // On the command line they override a body spec's values, and are refused there too.
  write(dir / "input-spec.yaml", "input: input-cube.geo\nunit: m\nmesh: {size: 0.5}\nreduction: {modes: 2}\n");
  expect_refusal(dir, "input-spec.yaml --mesh-size 0", "--mesh-size must be a positive number");
  expect_refusal(dir, "input-spec.yaml --modes 0", "--modes must be at least 1, got 0");
  // The spec's own keys (read_body_spec) name their line.
  write(dir / "input-zero-size.yaml", "input: input-cube.geo\nunit: m\nmesh: {size: 0}\n");
  expect_refusal(dir, "input-zero-size.yaml", "input-zero-size.yaml:3: mesh size must be positive, got 0");
  write(dir / "input-zero-modes.yaml", "input: input-cube.geo\nunit: m\nreduction: {modes: 0}\n");
  expect_refusal(dir, "input-zero-modes.yaml", "input-zero-modes.yaml:3: reduction modes must be at least 1");
  write(dir / "input-inf-fmax.yaml", "input: input-cube.geo\nunit: m\nreduction: {fmax: .inf}\n");
  expect_refusal(dir, "input-inf-fmax.yaml", "input-inf-fmax.yaml:3: reduction fmax must be finite");
  const CliRun surfaces = fbprep(dir, "list-surfaces input-cube.geo --unit m --mesh-size 0");
  EXPECT_EQ(surfaces.exit_code, 2);
  EXPECT_EQ(surfaces.out, "");
  EXPECT_EQ(surfaces.err.rfind("fbprep: error: --mesh-size must be a positive number", 0), 0u) << surfaces.err;
}

namespace {

/// A small body file (a steel box of 110 nodes, 2 modes), made once per test process in its own directory.
const std::filesystem::path& small_body_file() {
  static const std::filesystem::path file = [] {
    // Its own directory, apart from the running test's (scratch_dir), which it would empty, and apart from other
    // processes': ctest runs each test in a process of its own, two at a time, and one emptied the directory while
    // another copied the file from it (a CI failure).
    const auto dir = std::filesystem::path(FLEXBODY_TEST_SCRATCH_DIR) /
                     ("FbprepCli.small_body_file." + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    write(dir / "box.geo", std::string(kOcc) + "Box(1) = {0, 0, 0, 0.1, 0.02, 0.02};\n");
    const CliRun prep = fbprep(dir, "box.geo --unit m --mesh-size 0.02 --modes 2 -o box.fbh5 --quiet");
    EXPECT_EQ(prep.exit_code, 0) << prep.err;
    return dir / "box.fbh5";
  }();
  return file;
}

}  // namespace

// Issue 13: `fbprep seal IN -o OUT` replaced whatever OUT was. Like fbprep -o, an existing OUT is replaced only
// when it is a body file (or empty); OUT naming IN is the in-place re-seal.
TEST(FbprepCli, OutputReplacesOnlyBodyFiles) {
  const auto dir = flexbody::test::scratch_dir();
  std::filesystem::copy_file(small_body_file(), dir / "input-body.fbh5");
  write(dir / "input-notes.txt", "my notes\n");
  write(dir / "input-cube.geo", std::string(kOcc) + "Box(1) = {0, 0, 0, 1, 1, 1};\n");
  for (const std::string& arguments : {std::string("seal input-body.fbh5 -o input-notes.txt"),
                                       std::string("input-cube.geo --unit m --modes 2 -o input-notes.txt")}) {
    SCOPED_TRACE(arguments);
    const CliRun run = fbprep(dir, arguments);
    EXPECT_EQ(run.exit_code, 2);
    EXPECT_EQ(run.out, "");
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
    EXPECT_EQ(run.err.rfind("fbprep: error: input-notes.txt: the output exists and is not a body file", 0), 0u)
        << run.err;
    EXPECT_EQ(slurp(dir / "input-notes.txt"), "my notes\n");
    expect_no_output(dir);
  }
  // Nor a pipe (or a device: as root, renaming onto /dev/null would have replaced it); opening it would block.
  ASSERT_EQ(::mkfifo((dir / "input-pipe").c_str(), 0600), 0);
  for (const std::string& arguments : {std::string("seal input-body.fbh5 -o input-pipe"),
                                       std::string("input-cube.geo --unit m --modes 2 -o input-pipe")}) {
    SCOPED_TRACE(arguments);
    const CliRun run = fbprep(dir, arguments);
    EXPECT_EQ(run.exit_code, 2);
    EXPECT_EQ(run.err, "fbprep: error: input-pipe: the output exists and is not a regular file (a device, a pipe or a "
                       "socket); choose another output (-o)\n");
    EXPECT_TRUE(std::filesystem::is_fifo(dir / "input-pipe"));
    expect_no_output(dir);
  }
  // A body file, an empty file, a new name and the input itself (by another path) are written.
  std::filesystem::copy_file(small_body_file(), dir / "other.fbh5");
  write(dir / "empty.fbh5", "");
  for (const std::string& arguments : {std::string("seal input-body.fbh5 -o other.fbh5"),
                                       std::string("seal input-body.fbh5 -o empty.fbh5"),
                                       std::string("seal input-body.fbh5 -o new.fbh5"),
                                       std::string("seal input-body.fbh5 -o ./input-body.fbh5"),
                                       std::string("input-cube.geo --unit m --modes 2 -o other.fbh5 -q")}) {
    SCOPED_TRACE(arguments);
    const CliRun run = fbprep(dir, arguments);
    EXPECT_EQ(run.exit_code, 0) << run.err;
  }
  for (const char* name : {"other.fbh5", "empty.fbh5", "new.fbh5", "input-body.fbh5"})
    EXPECT_TRUE(flexbody::format::begins_like_body_file(dir / name)) << name;
}

// Issue 13: an input the user cannot read said "cannot be opened for reading" (or "cannot open the body spec")
// without why; it now says what the system says, as fbprep inspect did.
TEST(FbprepCli, UnreadableInputsSayWhy) {
  if (::geteuid() == 0) GTEST_SKIP() << "runs as root, which reads a file of mode 000 anyway";
  const auto dir = flexbody::test::scratch_dir();
  write(dir / "input-cube.geo", std::string(kOcc) + "Box(1) = {0, 0, 0, 1, 1, 1};\n");
  write(dir / "input-spec.yaml", "input: input-cube.geo\nunit: m\n");
  std::filesystem::permissions(dir / "input-spec.yaml", std::filesystem::perms::none);
  expect_refusal(dir, "input-spec.yaml", "input-spec.yaml: cannot open the body spec: Permission denied");
  std::filesystem::permissions(dir / "input-cube.geo", std::filesystem::perms::none);
  expect_refusal(dir, "input-cube.geo --unit m", "input-cube.geo: cannot be opened for reading: Permission denied");
  std::filesystem::permissions(dir / "input-spec.yaml", std::filesystem::perms::owner_read);
  expect_refusal(dir, "input-spec.yaml", "input-cube.geo: cannot be opened for reading: Permission denied");
}

// Issue 13: `fbprep inspect` printed the file's strings as they were: control characters reached the terminal and a
// name of any length was printed whole. Each is now shown escaped and cut after 200 bytes; --json cuts them too.
TEST(FbprepCli, InspectShowsTheFilesStringsSafely) {
  const auto dir = flexbody::test::scratch_dir();
  flexbody::format::BodyData body = flexbody::format::read_body_file(small_body_file());
  body.material.name = "steel\x1b[2J\x07\xc2\x9b" + std::string(1000, 'x');
  body.provenance.created_by = "fbprep\r\nforged line";
  body.provenance.options.emplace_back("note", "tab\there\x7f");
  flexbody::format::write_body_file(body, dir / "odd.fbh5");
  const CliRun report = fbprep(dir, "inspect odd.fbh5");
  ASSERT_EQ(report.exit_code, 0) << report.err;
  for (const char c : report.out) {
    const auto byte = static_cast<unsigned char>(c);
    EXPECT_TRUE(c == '\n' || (byte >= 0x20 && byte != 0x7f)) << "raw control character " << int{byte};
  }
  EXPECT_EQ(report.out.find("\xc2\x9b"), std::string::npos);  // U+009B, a C1 control (CSI)
  EXPECT_NE(report.out.find("steel\\x1b[2J\\x07\\u009b" + std::string(188, 'x') + "... (1012 bytes)"), std::string::npos)
      << report.out;
  EXPECT_NE(report.out.find("fbprep\\x0d\\x0aforged line"), std::string::npos) << report.out;
  EXPECT_NE(report.out.find("note=tab\\x09here\\x7f"), std::string::npos) << report.out;
  std::istringstream lines(report.out);
  for (std::string line; std::getline(lines, line);) EXPECT_LT(line.size(), 400u) << line;

  const CliRun json = fbprep(dir, "inspect odd.fbh5 --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const auto j = nlohmann::json::parse(json.out);
  EXPECT_EQ(j["material"]["name"], "steel\x1b[2J\x07\xc2\x9b" + std::string(188, 'x') + "... (1012 bytes)");
  EXPECT_EQ(j["created_by"], "fbprep\r\nforged line");
}

namespace {

volatile sig_atomic_t tested_signal = SIGTERM;
extern "C" void raise_tested_signal(int) { ::raise(tested_signal); }

}  // namespace

// Issue 13: a body file's temporary (.NAME.fbh5.tmp-PID-N) stayed behind when SIGTERM or Ctrl-C ended fbprep during
// the write. A child process calls remove_temporary_body_file_on_signal (as fbprep's main does) and writes a body
// file under a file-size limit far below its size: the write that crosses it raises SIGXFSZ, whose handler raises
// the tested signal. So the signal arrives inside write_body_file, while the temporary exists, every time.
TEST(FbprepCli, InterruptedWriteLeavesNoTemporary) {
  const flexbody::format::BodyData body = flexbody::format::read_body_file(small_body_file());
  const auto scratch = flexbody::test::scratch_dir();
  for (const int signal_number : {SIGTERM, SIGINT, SIGHUP}) {
    SCOPED_TRACE(signal_number);
    const auto dir = scratch / std::to_string(signal_number);
    std::filesystem::create_directories(dir);
    std::fflush(nullptr);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {  // only async-signal-safe work and the library's own until _exit
      // As in a foreground process: a shell starts background jobs with SIGINT ignored, which the function keeps.
      for (const int s : {SIGTERM, SIGINT, SIGHUP}) ::signal(s, SIG_DFL);
      flexbody::format::remove_temporary_body_file_on_signal();
      tested_signal = signal_number;
      struct sigaction crossed {};
      crossed.sa_handler = raise_tested_signal;
      sigemptyset(&crossed.sa_mask);
      ::sigaction(SIGXFSZ, &crossed, nullptr);
      const rlimit limit{8192, 8192};  // the body file takes about 150 kB
      ::setrlimit(RLIMIT_FSIZE, &limit);
      try {
        flexbody::format::write_body_file(body, dir / "body.fbh5");
      } catch (...) {
        ::_exit(3);
      }
      ::_exit(4);  // written under the limit: the test would show nothing
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status)) << "exit code " << (WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    EXPECT_EQ(WTERMSIG(status), signal_number);  // ended by the signal, as without the handler
    std::vector<std::string> left;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) left.push_back(entry.path().filename().string());
    EXPECT_TRUE(left.empty()) << "left behind: " << fmt::format("{}", fmt::join(left, ", "));
  }
}

// The mesh against the CAD volume from the command line (issue 28 item 2): --json gives the CAD volume, the error and
// the part's extent; a --mesh-size whose mesh misses the volume is refused in one line with a size that holds it, and
// nothing is written; --volume-tolerance accepts it. A cylinder r = 0.05 m, 0.2 m long, at 0.02 m misses 2 %
// (mesh_volume_test.cpp).
TEST(FbprepCli, TheMeshIsCheckedAgainstTheCadVolume) {
  const auto dir = flexbody::test::scratch_dir();
  write(dir / "input-cylinder.geo", std::string(kOcc) + "Cylinder(1) = {0, 0, 0, 0, 0, 0.2, 0.05};\n");
  expect_refusal(dir, "input-cylinder.geo --unit m --mesh-size 0.02 --order 1 --modes 2",
                 "input-cylinder.geo: the mesh at --mesh-size 0.02 m holds 98.");
  const CliRun accepted = fbprep(dir, "input-cylinder.geo --unit m --mesh-size 0.02 --order 1 --volume-tolerance 0.03 "
                                      "--modes 2 --json -o out.fbh5");
  ASSERT_EQ(accepted.exit_code, 0) << accepted.err;
  const nlohmann::json j = nlohmann::json::parse(accepted.out);
  EXPECT_NEAR(j["cad_volume_m3"].get<double>() / (std::numbers::pi * 0.05 * 0.05 * 0.2), 1.0, 1e-9);
  EXPECT_LT(j["volume_error"].get<double>(), -0.015);
  EXPECT_GT(j["volume_error"].get<double>(), -0.025);
  EXPECT_TRUE(j["mesh_size_refined_from_m"].is_null());
  // gmsh pads its bounding box by 1e-7 (in the model's units) on each side: 1.3e-6 of this diagonal
  EXPECT_NEAR(j["extent_m"].get<double>() / std::sqrt(0.1 * 0.1 * 2 + 0.2 * 0.2), 1.0, 1e-5);
  EXPECT_TRUE(j["size_warning"].is_null());
  EXPECT_EQ(accepted.err.find("across"), std::string::npos) << accepted.err;  // no size warning for a 0.24 m part
  // The default, quadratic tetrahedra, at the same size: their curved faces hold the volume (measured -3e-5).
  const CliRun quadratic = fbprep(dir, "input-cylinder.geo --unit m --mesh-size 0.02 --modes 2 --json -o quadratic.fbh5");
  ASSERT_EQ(quadratic.exit_code, 0) << quadratic.err;
  EXPECT_LT(std::abs(nlohmann::json::parse(quadratic.out)["volume_error"].get<double>()), 1e-3);
}

// A part 4 µm across (a 0.004 x 0.001 x 0.001 box read in mm: a unit mistake) is named before the work, on stderr
// (beside --json's stdout) and in --json; the run itself goes on (the scale tests show such parts solve right).
TEST(FbprepCli, APartOfImplausibleSizeIsNamed) {
  const auto dir = flexbody::test::scratch_dir();
  write(dir / "input-tiny.geo", std::string(kOcc) + "Box(1) = {0, 0, 0, 0.004, 0.001, 0.001};\n");
  const CliRun run = fbprep(dir, "input-tiny.geo --unit mm --modes 2 --json -o out.fbh5");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.err.rfind("fbprep: warning: the part is 4.24e-06 m across (bounding-box diagonal), read in "
                          "millimetres: smaller than 0.1 mm; check the unit", 0), 0u) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_NE(j["size_warning"].get<std::string>().find("smaller than 0.1 mm"), std::string::npos);
  EXPECT_EQ(fbprep(dir, "input-tiny.geo --unit mm --modes 2 -q -o out2.fbh5").err, "");  // -q: not even that
}
