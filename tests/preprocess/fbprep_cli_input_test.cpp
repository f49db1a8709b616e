// fbprep as a user runs it, its units and outputs: a STEP file's declared unit against the user's, what an output may
// replace, interrupted writes, the CAD volume and implausible sizes (each refusal one line on stderr, a non-zero exit,
// and no file under the output name).
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
