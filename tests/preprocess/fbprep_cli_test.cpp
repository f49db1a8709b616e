// fbprep as a user runs it: the bundled bracket end to end, inspect, export-vtu, quadratic elements, the mesher,
// list-surfaces, and refused inputs and options (fbprep_cli_input_test.cpp: units, outputs, interrupted writes).
#include "flexbody/format/body_file.hpp"
#include "flexbody/preprocess/eigensolver.hpp"
#include "flexbody/preprocess/stress_recovery.hpp"
#include "cli_run.hpp"
#include "fbprep_cli_helpers.hpp"
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

using namespace fbprep_cli;


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
  // docs/accuracy-and-speed.md measures +3.7 % at ten times the DOFs).
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
