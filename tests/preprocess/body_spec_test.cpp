// Body specs (fbprep body.yaml): a beam with two interfaces end to end, command-line overrides,
// paths relative to the spec, and every refusal as one line naming the spec's line.
#include "flexbody/format/body_file.hpp"
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <set>
#include <nlohmann/json.hpp>

namespace {

using flexbody::test::CliRun;
using flexbody::test::run_fbprep;
using flexbody::test::write_text;

// A steel beam 1 x 0.05 x 0.05 m as a .geo in metres, in a subfolder, and a spec beside it.
std::filesystem::path beam_folder() {
  const auto dir = flexbody::test::scratch_dir();
  std::filesystem::create_directories(dir / "part");
  write_text(dir / "part" / "beam.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 0.05, 0.05};\n");
  return dir;
}

constexpr const char* kBeamSpec = R"(# a beam hanging from one end
input: beam.geo
unit: m
material: {E: 210e9, nu: 0.3, rho: 7850}
mesh: {size: 0.025}
reduction: {kind: free-free, modes: 4}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}, coupling: rbe3}
  tip: {select: {box: {min: [0.999, -1, -1], max: [2, 1, 1]}}}
)";

void expect_spec_error(const std::string& spec, int line, const std::string& message) {
  SCOPED_TRACE(spec);
  const auto dir = beam_folder();
  write_text(dir / "part" / "bad.yaml", spec);
  const CliRun run = run_fbprep(dir, "part/bad.yaml -o out.fbh5");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  EXPECT_NE(run.err.find(fmt::format("fbprep: error: part/bad.yaml:{}: {}", line, message)), std::string::npos)
      << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.fbh5"));
}

}  // namespace

TEST(BodySpec, BeamWithTwoInterfacesEndToEnd) {
  const auto dir = beam_folder();
  write_text(dir / "part" / "beam.yaml", kBeamSpec);
  // Run from the folder above: input: beam.geo is found beside the spec, not in the working directory.
  const CliRun run = run_fbprep(dir, "part/beam.yaml -o beam.fbh5 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["frequencies_hz"].size(), 4u);
  ASSERT_EQ(json["interfaces"].size(), 2u);
  EXPECT_EQ(json["interfaces"][0]["name"], "root");
  EXPECT_EQ(json["interfaces"][1]["name"], "tip");
  EXPECT_EQ(json["interfaces"][1]["coupling"], "rbe3");  // the default

  const auto body = flexbody::format::read_body_file(dir / "beam.fbh5");
  ASSERT_EQ(body.interfaces.size(), 2u);
  // Both end faces are whole squares: area weights put their markers at the face centres.
  const Eigen::Vector3d root = body.interfaces[0].reference_point + body.mass.center_of_mass_input;
  const Eigen::Vector3d tip = body.interfaces[1].reference_point + body.mass.center_of_mass_input;
  EXPECT_LT((root - Eigen::Vector3d(0.0, 0.025, 0.025)).norm(), 1e-12);
  EXPECT_LT((tip - Eigen::Vector3d(1.0, 0.025, 0.025)).norm(), 1e-12);
  EXPECT_EQ(body.interfaces[0].y_row.size(), 4 + body.gcms.field_count());
  // Provenance keeps the spec and what it resolved to.
  bool has_spec = false;
  for (const auto& [name, value] : body.provenance.options) has_spec = has_spec || (name == "spec" && value == "part/beam.yaml");
  EXPECT_TRUE(has_spec);
}

TEST(BodySpec, CommandLineFlagsOverrideTheSpec) {
  const auto dir = beam_folder();
  write_text(dir / "part" / "beam.yaml", kBeamSpec);
  const CliRun run = run_fbprep(dir, "part/beam.yaml -o beam.fbh5 --modes 2 --material aluminium --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["frequencies_hz"].size(), 2u);
  EXPECT_EQ(json["material"]["name"], "aluminium");
  EXPECT_EQ(json["interfaces"].size(), 2u);  // the rest of the spec still holds
}

// mesh: {order: 2} gives quadratic tetrahedra (issue 15), algorithm: hxt gmsh's HXT mesher; --order on the command line
// replaces the order like every flag; an
// output region may be the whole surface.
TEST(BodySpec, ElementOrderFromTheSpecAndItsOverride) {
  const auto dir = beam_folder();
  std::string spec = kBeamSpec;
  spec.replace(spec.find("mesh: {size: 0.025}"), 19, "mesh: {size: 0.05, order: 2, algorithm: hxt}");
  spec += "output_regions:\n  skin: {select: surface}\n";
  write_text(dir / "part" / "beam.yaml", spec);
  const CliRun quadratic = run_fbprep(dir, "part/beam.yaml -o q.fbh5 --json");
  ASSERT_EQ(quadratic.exit_code, 0) << quadratic.err;
  EXPECT_EQ(nlohmann::json::parse(quadratic.out)["element_order"], 2);
  EXPECT_EQ(nlohmann::json::parse(quadratic.out)["mesher"], "hxt");
  const CliRun linear = run_fbprep(dir, "part/beam.yaml -o l.fbh5 --order 1 --json");
  ASSERT_EQ(linear.exit_code, 0) << linear.err;
  EXPECT_EQ(nlohmann::json::parse(linear.out)["element_order"], 1);
  const flexbody::format::BodyData body = flexbody::format::read_body_file(dir / "q.fbh5");
  bool recorded = false;
  for (const auto& [name, value] : body.provenance.options)
    recorded = recorded || (name == "element_order" && value == "2");
  EXPECT_TRUE(recorded);
  // mesh: {thin_features: N} (GmshImportOptions::thin_feature_elements) is read and recorded; the beam's shortest
  // curves, its 50 mm edges, ask for 25 mm at 2 across, finer than the 50 mm size: more elements.
  std::string thin = spec;
  thin.replace(thin.find("algorithm: hxt}"), 15, "thin_features: 2}");
  write_text(dir / "part" / "thin.yaml", thin);
  const CliRun fine = run_fbprep(dir, "part/thin.yaml -o t.fbh5 --order 1 --json");
  ASSERT_EQ(fine.exit_code, 0) << fine.err;
  EXPECT_GT(nlohmann::json::parse(fine.out)["elements"].get<int>(), nlohmann::json::parse(linear.out)["elements"].get<int>());
  bool thin_recorded = false;
  for (const auto& [name, value] : flexbody::format::read_body_file(dir / "t.fbh5").provenance.options)
    thin_recorded = thin_recorded || (name == "thin_features" && value == "2");
  EXPECT_TRUE(thin_recorded);
  const CliRun refused = run_fbprep(dir, "part/beam.yaml -o r.fbh5 --thin-features -1");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("--thin-features must be a positive number"), std::string::npos) << refused.err;
  // select: surface takes every boundary node (corners and mid-edge nodes), no other.
  std::set<int> boundary(body.mesh.surface_triangles.data(),
                         body.mesh.surface_triangles.data() + body.mesh.surface_triangles.size());
  ASSERT_EQ(body.recovery.size(), 1u);
  EXPECT_EQ(body.recovery[0].name, "skin");
  EXPECT_EQ(std::set<int>(body.recovery[0].nodes.data(), body.recovery[0].nodes.data() + body.recovery[0].nodes.size()),
            boundary);
}

TEST(BodySpec, RefusalsNameTheLine) {
  const std::string head = "input: beam.geo\nunit: m\n";
  expect_spec_error(head + "colour: red\n", 3, "unknown key 'colour' in the body spec");
  expect_spec_error(head + "material: {E: .nan, nu: 0.3, rho: 7850}\n", 3, "material E must be finite, got '.nan'");
  expect_spec_error(head + "material: {E: 210e9, nu: 0.6, rho: 7850}\n", 3, "material: nu must lie in (-1, 0.5), got 0.6");
  expect_spec_error(head + "mesh: {size: -1}\n", 3, "mesh size must be positive, got -1");
  expect_spec_error(head + "mesh: {thin_features: 0}\n", 3, "mesh thin_features must be positive, got 0");
  expect_spec_error(head + "mesh: {size: 0.02}\nmesh: {size: 0.03}\n", 4, "key 'mesh' is repeated in the body spec");
  expect_spec_error(head + "mesh: {order: 3}\n", 3, "mesh order 3: the element order is 1 (linear tetrahedra) or 2");
  expect_spec_error(head + "mesh: {algorithm: tetgen}\n", 3, "mesh algorithm 'tetgen' is unknown; use delaunay or hxt");
  expect_spec_error("unit: m\n", 1, "the body spec needs 'input'");
  expect_spec_error("input: beam.geo\nunit: furlong\n", 2, "unit 'furlong' is not one of mm, cm, m, in");
  expect_spec_error(head + "reduction: {modes: many}\n", 3, "reduction modes must be a number, got 'many'");
  expect_spec_error(head + "interfaces:\n  root: {select: {sphere: {}}}\n", 4, "unknown key 'sphere' in interface 'root' select");
  expect_spec_error(head + "interfaces:\n  root: {select: {plane: {point: [0, 0], normal: [1, 0, 0]}}}\n", 4,
                    "interface 'root' plane point must be a list of 3 numbers");
  expect_spec_error(head + "interfaces:\n  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}, coupling: glue}\n",
                    4, "interface 'root': coupling 'glue' is unknown");
  expect_spec_error(head + "material: {E: 210e9, nu: 0.3, rho: [7850\n", 4, "end of sequence flow not found");  // YAML syntax
  expect_spec_error(head + "reduction: {kind: guyan}\n", 3, "reduction kind 'guyan' is unknown");
  expect_spec_error(head + "load_points: [[1, 0, 0]]\n", 3, "load_points must be a map of names to load points");
  const std::string tip = "{select: {plane: {point: [1, 0, 0], normal: [1, 0, 0]}}";
  expect_spec_error(head + "load_points:\n  hook: " + tip + ", loads: [fx, fw]}\n", 4,
                    "load point 'hook': load 'fw' is unknown; use fx, fy, fz, mx, my, mz");
  expect_spec_error(head + "load_points:\n  hook: " + tip + ", loads: [fx, fx]}\n", 4,
                    "load point 'hook': load 'fx' is listed twice");
  expect_spec_error(head + "interfaces:\n  a: " + tip + "}\nload_points:\n  a: " + tip + "}\n", 6,
                    "load point 'a': the name is already an interface or load point");
  expect_spec_error(head + "output_regions:\n  top: {select: everywhere}\n", 4,
                    "output region 'top' select must be a selector map, 'all' (every node) or 'surface' (every boundary node), got 'everywhere'");
  expect_spec_error(head + "output_regions:\n  \"a,b\": {select: all}\n", 4,
                    "output region 'a,b': the name is not allowed");
  expect_spec_error(head + "interfaces:\n  root: {select: {surfaces: [0]}}\n", 4,
                    "interface 'root' surfaces tags start at 1, got 0");
  expect_spec_error(head + "interfaces:\n  root: {select: {surfaces: 3}}\n", 4,
                    "interface 'root' surfaces must be a list of surface tags");
}

TEST(BodySpec, SurfaceTagsAndPhysicalGroupsSelectCadFaces) {
  // The same end faces three ways: by plane, by CAD surface tag, by physical group. OpenCASCADE numbers
  // a box's faces x-min, x-max, y-min, y-max, z-min, z-max: surface 2 is the face at x = 1.
  const auto dir = flexbody::test::scratch_dir();
  write_text(dir / "beam.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 0.05, 0.05};\n"
                               "Physical Surface(\"clamp\") = {1};\nPhysical Volume(\"steel\") = {1};\n");
  write_text(dir / "beam.yaml",
             "input: beam.geo\nunit: m\nmesh: {size: 0.025}\nreduction: {modes: 2}\ninterfaces:\n"
             "  by_group: {select: {group: clamp}}\n  by_tag: {select: {surfaces: [2]}}\n");
  const CliRun run = run_fbprep(dir, "beam.yaml -o beam.fbh5 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto body = flexbody::format::read_body_file(dir / "beam.fbh5");
  ASSERT_EQ(body.interfaces.size(), 2u);
  const Eigen::Vector3d group_point = body.interfaces[0].reference_point + body.mass.center_of_mass_input;
  const Eigen::Vector3d tag_point = body.interfaces[1].reference_point + body.mass.center_of_mass_input;
  EXPECT_LT((group_point - Eigen::Vector3d(0.0, 0.025, 0.025)).norm(), 1e-12);
  EXPECT_LT((tag_point - Eigen::Vector3d(1.0, 0.025, 0.025)).norm(), 1e-12);
  // Same nodes as the plane x = 0 takes.
  write_text(dir / "plane.yaml", "input: beam.geo\nunit: m\nmesh: {size: 0.025}\nreduction: {modes: 2}\ninterfaces:\n"
                                 "  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}}\n");
  ASSERT_EQ(run_fbprep(dir, "plane.yaml -o plane.fbh5").exit_code, 0);
  EXPECT_EQ(flexbody::format::read_body_file(dir / "plane.fbh5").interfaces[0].nodes, body.interfaces[0].nodes);

  write_text(dir / "bad.yaml", "input: beam.geo\nunit: m\ninterfaces:\n  x: {select: {surfaces: [99]}}\n");
  const CliRun missing = run_fbprep(dir, "bad.yaml -o bad.fbh5");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("interface 'x': the part has no surface 99 (surfaces: 1, 2, 3, 4, 5, 6; see fbprep "
                             "list-surfaces)"), std::string::npos) << missing.err;
  write_text(dir / "bad.yaml", "input: beam.geo\nunit: m\ninterfaces:\n  x: {select: {group: flange}}\n");
  const CliRun no_group = run_fbprep(dir, "bad.yaml -o bad.fbh5");
  EXPECT_NE(no_group.err.find("interface 'x': the part has no surface group 'flange' (groups: clamp)"),
            std::string::npos) << no_group.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.fbh5"));
}

TEST(BodySpec, TheIssuesCraigBamptonExampleWorks) {
  // The spec of the issue, on the beam as a .geo: Craig-Bampton with an rbe2 root.
  const auto dir = beam_folder();
  write_text(dir / "part" / "cb.yaml", R"(input: beam.geo
unit: m
material: {E: 210e9, nu: 0.3, rho: 7850}
mesh: {size: 0.0125}
reduction: {kind: craig-bampton, modes: 8}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}, coupling: rbe2}
)");
  const CliRun run = run_fbprep(dir, "part/cb.yaml -o cb.fbh5 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["reduction"], "craig-bampton");
  ASSERT_EQ(json["fixed_interface_frequencies_hz"].size(), 8u);
  EXPECT_EQ(json["frequencies_hz"].size(), 8u);  // 8 fixed + 6 constraint modes - 6 rigid
  // The clamped pair is the cantilever's first bending pair, Timoshenko 41.69 Hz; linear tets on this
  // mesh lock by a few per cent (validation/README.md: 42.2-53 Hz on structured meshes).
  const double f1 = json["fixed_interface_frequencies_hz"][0].get<double>();
  EXPECT_GT(f1, 41.69);
  EXPECT_LT(f1, 1.15 * 41.69);
  // The orthonormalised basis holds the free body: its first frequency is a Rayleigh-Ritz upper bound of
  // the free-free first bending mode (Timoshenko 263.46 Hz, +locking).
  EXPECT_GT(json["frequencies_hz"][0].get<double>(), 263.46);
  const auto body = flexbody::format::read_body_file(dir / "cb.fbh5");  // every reader check passes
  EXPECT_EQ(body.modes.kind, "craig-bampton");
  EXPECT_EQ(body.modes.fixed_interface_frequencies_hz.size(), 8);
  ASSERT_EQ(body.interfaces.size(), 1u);
  EXPECT_EQ(body.interfaces[0].coupling, "rbe2");
  const CliRun inspect = run_fbprep(dir, "inspect cb.fbh5 --json");
  ASSERT_EQ(inspect.exit_code, 0) << inspect.err;
  EXPECT_EQ(nlohmann::json::parse(inspect.out)["fixed_interface_frequencies_hz"], json["fixed_interface_frequencies_hz"]);
}

TEST(BodySpec, SlenderCraigBamptonBeamOfIssue12IsAccepted) {
  // The spec of issue 12: a plastic beam 1 x 0.04 x 0.02 m clamped by an rbe2 root, 16 fixed-interface modes.
  // 521de58 refused it ("fixed-interface mode 1 (6.57335 Hz) has relative residual 1.78e-08 > 1e-8"): that mode's
  // rounding floor is 2.9e-8, so 1e-8 asked for more than double precision gives. Now each mode is judged
  // against its own floor, and the report and --json give both numbers.
  const auto dir = flexbody::test::scratch_dir();
  write_text(dir / "slender.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 0.04, 0.02};\n");
  write_text(dir / "slender.yaml", R"(input: slender.geo
unit: m
material: {E: 5e9, nu: 0.3, rho: 2000}
mesh: {size: 0.01}
reduction: {kind: craig-bampton, modes: 16}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}, coupling: rbe2}
output_regions: {}
)");
  const CliRun run = run_fbprep(dir, "slender.yaml -o slender.fbh5 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  ASSERT_EQ(json["fixed_interface_relative_residuals"].size(), 16u);
  ASSERT_EQ(json["fixed_interface_residual_floors"].size(), 16u);
  EXPECT_EQ(json["residual_floors"].size(), 0u);  // the orthonormalised modes' residuals are reduction errors
  EXPECT_EQ(json["residual_acceptance"]["min_bound"].get<double>(), 1e-8);
  EXPECT_EQ(json["residual_acceptance"]["floor_factor"].get<double>(), 20.0);
  // The first mode's floor lies above the old bound (2.9e-8 measured; it depends on the vector only to rounding).
  EXPECT_GT(json["fixed_interface_residual_floors"][0].get<double>(), 1e-8);
  // Every mode near its floor: 0.44 to 1.3 of it measured (converged modes in general: up to 8.6).
  EXPECT_LT(json["max_residual_to_floor"].get<double>(), 5.0);
  // The first two are the bending modes about the thin and the thick side: Euler-Bernoulli 1.875² √(EI/ρA) /
  // (2π L²) = 5.108 and 10.216 Hz. Two linear tets through the 0.02 m side lock: measured +29 % and +7 %.
  const double f1 = json["fixed_interface_frequencies_hz"][0].get<double>();
  const double f2 = json["fixed_interface_frequencies_hz"][1].get<double>();
  EXPECT_GT(f1, 5.108);
  EXPECT_LT(f1, 1.35 * 5.108);
  EXPECT_GT(f2, 10.216);
  EXPECT_LT(f2, 1.15 * 10.216);

  const CliRun report = run_fbprep(dir, "slender.yaml -o slender.fbh5");
  ASSERT_EQ(report.exit_code, 0) << report.err;
  EXPECT_NE(report.out.find("rel. residual  rounding floor"), std::string::npos) << report.out;
  EXPECT_NE(report.out.find("accepted: residual <= max(1e-08, 20 x floor)"), std::string::npos) << report.out;
}

TEST(BodySpec, LoadPointsAndOutputRegions) {
  // A free-free beam with a load point at its tip (fy and mz only) and one output region at its root.
  const auto dir = beam_folder();
  write_text(dir / "part" / "loads.yaml", R"(input: beam.geo
unit: m
mesh: {size: 0.025}
reduction: {modes: 4}
load_points:
  tip: {select: {plane: {point: [1, 0, 0], normal: [1, 0, 0]}}, loads: [fy, mz]}
output_regions:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}}
)");
  const CliRun run = run_fbprep(dir, "part/loads.yaml -o loads.fbh5 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["static_loads"], nlohmann::json::array({"tip:fy", "tip:mz"}));
  EXPECT_EQ(json["static_correction"]["loads"], 2);
  EXPECT_EQ(json["static_correction"]["dropped"], 0);
  EXPECT_EQ(json["static_correction"]["modes"], 2);
  // The CG stops at 1e-10 of the projected load; the true residual adds rounding.
  EXPECT_LT(json["static_correction"]["max_relative_residual"].get<double>(), 1e-9);
  ASSERT_EQ(json["frequencies_hz"].size(), 6u);
  EXPECT_EQ(json["output_regions"][0]["name"], "root");

  const auto body = flexbody::format::read_body_file(dir / "loads.fbh5");
  EXPECT_EQ(body.modes.static_correction_modes, 2);
  EXPECT_EQ(body.modes.static_loads, (std::vector<std::string>{"tip:fy", "tip:mz"}));
  ASSERT_EQ(body.interfaces.size(), 1u);  // the load point is an rbe3 marker
  EXPECT_EQ(body.interfaces[0].name, "tip");
  EXPECT_EQ(body.interfaces[0].coupling, "rbe3");
  // The static corrections are Ritz vectors above the normal modes; the normal modes keep their residuals.
  EXPECT_GT(body.modes.frequencies_hz(4), body.modes.frequencies_hz(3));
  EXPECT_LT(body.modes.relative_residuals.head(4).maxCoeff(), 1e-8);
  ASSERT_EQ(body.recovery.size(), 1u);
  const auto& root = body.recovery[0];
  for (Eigen::Index j = 0; j < root.nodes.size(); ++j)  // the root face: x = 0 in the input frame
    EXPECT_NEAR(body.mesh.nodes(root.nodes(j), 0) + body.mass.center_of_mass_input(0), 0.0, 1e-12);
  EXPECT_EQ(root.stress_modes.rows(), 6 * root.nodes.size());
  EXPECT_EQ(root.stress_modes.cols(), 3 * body.gcms.field_count());

  // Without output_regions a mesh this small gets the whole body; with an empty map, none.
  write_text(dir / "part" / "whole.yaml", "input: beam.geo\nunit: m\nmesh: {size: 0.025}\nreduction: {modes: 2}\n");
  ASSERT_EQ(run_fbprep(dir, "part/whole.yaml -o whole.fbh5 -q").exit_code, 0);
  const auto whole = flexbody::format::read_body_file(dir / "whole.fbh5");
  ASSERT_EQ(whole.recovery.size(), 1u);
  EXPECT_EQ(whole.recovery[0].name, "body");
  EXPECT_EQ(whole.recovery[0].nodes.size(), whole.mesh.nodes.rows());
  write_text(dir / "part" / "none.yaml",
             "input: beam.geo\nunit: m\nmesh: {size: 0.025}\nreduction: {modes: 2}\noutput_regions: {}\n");
  ASSERT_EQ(run_fbprep(dir, "part/none.yaml -o none.fbh5 -q").exit_code, 0);
  EXPECT_TRUE(flexbody::format::read_body_file(dir / "none.fbh5").recovery.empty());
}

TEST(BodySpec, RigidTieNeedsCraigBampton) {
  // rbe2 ties the nodes rigidly; free-free modes cannot honour that, so fbprep refuses before meshing.
  const auto dir = beam_folder();
  write_text(dir / "part" / "tied.yaml",
             "input: beam.geo\nunit: m\ninterfaces:\n  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}, "
             "coupling: rbe2}\n");
  const CliRun run = run_fbprep(dir, "part/tied.yaml -o out.fbh5");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("interface 'root': coupling rbe2 ties its nodes rigidly, which changes the modes; "
                         "free-free modes take rbe3 interfaces only"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.fbh5"));
}

namespace {

// The beam of beam_folder() as a STEP file written by gmsh: numbers in metres, declared mm.
std::filesystem::path step_beam_folder() {
  const auto dir = flexbody::test::scratch_dir();
  std::filesystem::create_directories(dir / "part");
  std::filesystem::copy_file(std::filesystem::path(FLEXBODY_TEST_DATA_DIR) / "gmsh-beam" / "beam_1m.step",
                             dir / "part" / "beam.step");
  return dir;
}

// Every length below is in the spec's unit (issue 12): plane points and tolerances, boxes, the mesh size.
constexpr const char* kStepBeamSpec = R"(input: beam.step
unit: {unit}
mesh: {{size: 0.025}}
reduction: {{modes: 2}}
interfaces:
  root: {{select: {{plane: {{point: [0, 0, 0], normal: [1, 0, 0]}}}}}}
  tip: {{select: {{plane: {{point: [1, 0, 0], normal: [1, 0, 0], tolerance: 0.001}}}}}}
output_regions:
  middle: {{select: {{box: {{min: [0.4, -1, -1], max: [0.6, 1, 1]}}}}}}
)";

// The markers of a body made from kStepBeamSpec sit on the beam's end faces, read as `length` long.
void expect_beam_of_length(const std::filesystem::path& file, double length) {
  const auto body = flexbody::format::read_body_file(file);
  ASSERT_EQ(body.interfaces.size(), 2u);
  const Eigen::Vector3d com = body.mass.center_of_mass_input;
  const double s = length;  // the cross-section scales with the length
  EXPECT_LT((body.interfaces[0].reference_point + com - Eigen::Vector3d(0, 0.025, 0.025) * s).norm(), 1e-12 * s);
  EXPECT_LT((body.interfaces[1].reference_point + com - Eigen::Vector3d(1, 0.025, 0.025) * s).norm(), 1e-12 * s);
  // A box's tetrahedra fill it exactly: mass = 7850 kg/m^3 x volume to rounding.
  EXPECT_NEAR(body.mass.mass, 7850 * 0.0025 * s * s * s, 1e-9 * 7850 * 0.0025 * s * s * s);
  ASSERT_EQ(body.recovery.size(), 1u);
  const Eigen::VectorXi& middle = body.recovery[0].nodes;
  ASSERT_GT(middle.size(), 0);
  for (Eigen::Index j = 0; j < middle.size(); ++j) {
    const double x = body.mesh.nodes(middle(j), 0) + com(0);
    EXPECT_GE(x, (0.4 - 1e-12) * s);  // to rounding: the box takes nodes on its faces
    EXPECT_LE(x, (0.6 + 1e-12) * s);
  }
}

}  // namespace

TEST(BodySpec, UnitAppliesToTheCoordinatesAndEveryLengthOfAStepInput) {
  // A spec's unit: m on a STEP file that declares mm (gmsh's writer always does) is the unit of the
  // file's numbers and of the spec's selectors, tolerances and mesh size: the beam is 1 m long and the
  // plane at x = 1 takes its end face.
  const auto dir = step_beam_folder();
  write_text(dir / "part" / "beam.yaml", fmt::format(kStepBeamSpec, fmt::arg("unit", "m")));
  const CliRun run = run_fbprep(dir, "part/beam.yaml -o beam.fbh5 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["length_unit"], "m");
  EXPECT_EQ(json["declared_unit"], "mm");
  EXPECT_EQ(json["length_unit_reason"],
            "the STEP file declares mm; the body spec's unit: m overrides it: coordinates read as metres");
  EXPECT_NEAR(json["mesh_size_m"].get<double>(), 0.025, 1e-15);
  expect_beam_of_length(dir / "beam.fbh5", 1.0);
  EXPECT_EQ(flexbody::format::read_body_file(dir / "beam.fbh5").provenance.declared_unit, "mm");
}

TEST(BodySpec, CommandLineUnitOverridesTheSpecUnit) {
  // bracket.step declares mm. A spec that says unit: m reads its numbers, and the spec's own lengths, as
  // metres (a 90 m bracket with its bores where the spec puts them); --unit mm replaces the spec's unit, as
  // any flag replaces the spec's value, and the same numbers are then millimetres, spec and part alike.
  const auto dir = flexbody::test::scratch_dir();
  const auto bracket = std::filesystem::path(FLEXBODY_SOURCE_DIR) / "meshes" / "bracket.step";
  write_text(dir / "bracket.yaml", fmt::format(R"(input: {}
unit: m
mesh: {{size: 6, volume_tolerance: 0.01}}  # 6 mm holds 100.7 % of the volume
reduction: {{modes: 2}}
interfaces:
  bore_1: {{select: {{cylinder: {{point: [45, 20, 0], direction: [0, 0, 1], radius: 5}}}}}}
  bore_3: {{select: {{cylinder: {{point: [0, 20, 42], direction: [1, 0, 0], radius: 6}}}}}}
output_regions: {{}}
)", bracket.string()));
  // Area centroids of the faceted bores: on their axes (to ~1e-5 of the bracket's size at this mesh) and
  // mid-way through the 8-unit wall.
  auto expect_bores = [](const std::filesystem::path& file, double metres_per_number) {
    const auto body = flexbody::format::read_body_file(file);
    ASSERT_EQ(body.interfaces.size(), 2u);
    const Eigen::Vector3d expected[2] = {{45, 20, 4}, {4, 20, 42}};
    for (int k = 0; k < 2; ++k)
      EXPECT_LT((body.interfaces[k].reference_point + body.mass.center_of_mass_input - expected[k] * metres_per_number)
                    .norm(), 0.05 * metres_per_number) << body.interfaces[k].name;
  };
  const CliRun metres = run_fbprep(dir, "bracket.yaml -o m.fbh5 --json");
  ASSERT_EQ(metres.exit_code, 0) << metres.err;
  const auto m = nlohmann::json::parse(metres.out);
  EXPECT_EQ(m["length_unit"], "m");
  EXPECT_EQ(m["length_unit_reason"],
            "the STEP file declares mm; the body spec's unit: m overrides it: coordinates read as metres");
  expect_bores(dir / "m.fbh5", 1.0);

  const CliRun millimetres = run_fbprep(dir, "bracket.yaml -o mm.fbh5 --unit mm --json");
  ASSERT_EQ(millimetres.exit_code, 0) << millimetres.err;
  const auto mm = nlohmann::json::parse(millimetres.out);
  EXPECT_EQ(mm["length_unit"], "mm");
  EXPECT_EQ(mm["unit_overrides_declared"], false);
  EXPECT_EQ(mm["length_unit_reason"], "declared in the STEP file (mm); --unit mm (replacing the body spec's unit: m) agrees");
  expect_bores(dir / "mm.fbh5", 1e-3);
  EXPECT_NEAR(m["mass_kg"].get<double>() / mm["mass_kg"].get<double>(), 1e9, 1e-9 * 1e9);  // the same mesh
  bool recorded = false;
  for (const auto& [name, value] : flexbody::format::read_body_file(dir / "mm.fbh5").provenance.options)
    recorded = recorded || (name == "unit" && value == "mm");
  EXPECT_TRUE(recorded);
}
