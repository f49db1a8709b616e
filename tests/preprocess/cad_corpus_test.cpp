// Public CAD parts that nobody here wrote (issue 28): FreeCAD's Idf component models, from Debian's freecad-common
// (scripts/setup.sh installs it). bench/cad_corpus_bench.py runs the whole library through fbprep; these tests keep
// the parts that once failed working.
#include "flexbody/preprocess/curved_mesh_repair.hpp"
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/mesh_topology.hpp"
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <gmsh.h>

#include <cctype>
#include <cstdlib>
#include <ostream>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace fp = flexbody::preprocess;

namespace {

const std::filesystem::path kFreecadParts = "/usr/share/freecad/Mod/Idf/Idflibs";

fp::ImportedMesh import_part(const std::string& name, int order) {
  fp::GmshImportOptions options;
  options.order = order;
  return fp::import_tet_mesh(kFreecadParts / name, options);
}

}  // namespace

// Quadratic tetrahedra at the default size on parts with small fillets and thin leads: gmsh raises the order with
// mid-edge nodes on the curved surfaces, which folds some elements (before issue 28 fbprep refused these parts). Its
// elastic smoothing cures all of SOT_323_3's (30 with gmsh 4.8.4); on MSOP_10 it leaves 18 of 50 and straightening
// does the rest, moving nodes by up to 4.2 % of the element size. Either way no element is folded, the curved
// mesh's volume is the linear one's to 0.5 % (measured 0.03 % and 0.09 %: both resolve the same CAD solid, the
// curved one its curved faces better), and the smallest Jacobian ratio is positive.
TEST(CadCorpus, QuadraticMeshesOfPartsWithFilletsAreRepaired) {
  if (!std::filesystem::is_directory(kFreecadParts))
    GTEST_SKIP() << kFreecadParts << " is missing: scripts/setup.sh installs Debian's freecad-common";
  for (const std::string part : {"SOT_323_3.stp", "MSOP_10.stp"}) {
    SCOPED_TRACE(part);
    const fp::ImportedMesh linear = import_part(part, 1);
    const fp::ImportedMesh quadratic = import_part(part, 2);
    ASSERT_TRUE(quadratic.quadratic && quadratic.curved_repair);
    EXPECT_FALSE(linear.curved_repair.has_value());
    const fp::CurvedElementRepair& repair = *quadratic.curved_repair;
    EXPECT_GT(repair.folded, 0);
    EXPECT_GE(repair.after_elastic, 0);
    EXPECT_LT(repair.after_elastic, repair.folded);
    EXPECT_EQ(repair.straightened.elements > 0, repair.after_elastic > 0);
    EXPECT_LT(repair.straightened.largest_move_m, 0.1 * quadratic.mesh_size_m);
    EXPECT_TRUE(fp::folded_elements(*quadratic.quadratic).empty());
    const fp::MeshQuality quality = fp::mesh_quality(*quadratic.quadratic);
    EXPECT_GT(quality.min_jacobian_ratio, 0.0);
    EXPECT_NEAR(quality.volume_m3 / fp::mesh_quality(linear.mesh).volume_m3, 1.0, 5e-3);
  }
}

// Surface-only models (before issue 28 every one was refused with "the input has no volume"): SOT23's 73 faces, STEP
// and IGES alike, close one shell and are sewn into a solid whose mesh holds its CAD volume (both files: the same
// 3.55e-9 m³ to 1e-4, measured 2e-5). RLF_12545.igs's faces close 3 shells side by side (its STEP file holds 3
// solids): an assembly, refused as one. SOD_323's stay open along 34 free edges: refused naming them.
TEST(CadCorpus, SurfaceModelsAreSewnOrRefused) {
  if (!std::filesystem::is_directory(kFreecadParts))
    GTEST_SKIP() << kFreecadParts << " is missing: scripts/setup.sh installs Debian's freecad-common";
  const fp::ImportedMesh step = import_part("SOT23.stp", 1), iges = import_part("SOT23.igs", 1);
  EXPECT_EQ(step.sewn_faces, 73);
  EXPECT_EQ(iges.sewn_faces, 73);
  ASSERT_TRUE(step.cad_volume_m3 && iges.cad_volume_m3);
  EXPECT_NEAR(*step.cad_volume_m3 / *iges.cad_volume_m3, 1.0, 1e-4);
  EXPECT_NEAR(fp::mesh_quality(step.mesh).volume_m3 / *step.cad_volume_m3, 1.0, 5e-3);
  for (const auto& [part, message] :
       {std::pair<std::string, std::string>{"RLF_12545.igs", "sewn, they make 3 closed shells: an assembly is not one body"},
        {"SOD_323.stp", "sewing them made no closed solid: 34 free edges"}}) {
    SCOPED_TRACE(part);
    try {
      (void)import_part(part, 1);
      ADD_FAILURE() << "taken";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

// Linear elements at the default size on parts with thin leads are far off, and fbprep now refines them and says how
// far off they still are (issue 28 items 2 and 5: the table, against refined quadratic references: RLF_7030
// 16.3 kHz against 5.58 kHz, TCMT1107_4 44.1 kHz against 19.6 kHz, TSS0P_8 115 kHz against 58.7 kHz, i.e. 96-192 %
// too high). The first meshes' estimates (measured 133 %, 122 %, 96 %) are above 50 %; the refinement by the error
// estimate (mesh_refinement.hpp) is bound by its budget of 8 times the tetrahedra and leaves 38 %, 23 %, 21 %
// (6.67, 23.8 and 69.9 kHz), above the 5 % that warns: each run warns on stderr and in --json, with the way out. 1210_SMD, a
// compact block, is 3.0 % off (its quadratic mesh: 444.9 against 458.2 kHz): estimated 2.8 %, not refined, no warning.
TEST(CadCorpus, LinearElementsThatAreFarOffAreFlagged) {
  if (!std::filesystem::is_directory(kFreecadParts))
    GTEST_SKIP() << kFreecadParts << " is missing: scripts/setup.sh installs Debian's freecad-common";
  const auto dir = flexbody::test::scratch_dir();
  for (const std::string part : {"RLF_7030.stp", "TCMT1107_4.stp", "TSS0P_8.stp", "1210_SMD.stp"}) {
    SCOPED_TRACE(part);
    const flexbody::test::CliRun run =
        flexbody::test::run_fbprep(dir, fmt::format("'{}' --order 1 --json -o out.fbh5", (kFreecadParts / part).string()));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const nlohmann::json j = nlohmann::json::parse(run.out);
    const double first = j["frequency_error_estimates"][0].get<double>();
    if (part == "1210_SMD.stp") {
      EXPECT_LT(first, 0.05);
      EXPECT_GT(first, 0.01);
      EXPECT_TRUE(j["mesh_refinement"].is_null());
      EXPECT_TRUE(j["accuracy_warning"].is_null());
      EXPECT_EQ(run.err, "");
    } else {
      EXPECT_GT(j["mesh_refinement"]["first_estimate"].get<double>(), 0.5);
      EXPECT_TRUE(j["mesh_refinement"]["budget_bound"].get<bool>());
      EXPECT_LT(first, 0.5 * j["mesh_refinement"]["first_estimate"].get<double>());
      EXPECT_GT(first, 0.05);
      EXPECT_FALSE(j["accuracy_warning"].is_null());
      EXPECT_EQ(run.err.rfind("fbprep: warning: the first frequency", 0), 0u) << run.err;
      // With a size to try, in the input's unit: the error of an eigenvalue falls like h² with linear elements, so
      // h (2.5 % / e)^(1/2), below 0.4 of the mesh size for these estimates.
      EXPECT_NE(run.err.find("use --order 2, or a smaller --mesh-size (about "), std::string::npos) << run.err;
      EXPECT_NE(run.err.find(" mm, 0."), std::string::npos) << run.err;
    }
  }
}

// The whole corpus (issue 28 item 6), one ctest per part and element order, at fbprep's defaults: every STEP and
// IGES model of FreeCAD's Idf library, gmsh's demo part component8.step and the 18 solids of its demo assembly
// as1-tu-203, each written on its own as BREP (read in mm). Each gives a body file whose mass is the CAD solid's
// volume times the density to 0.5 % (the default --volume-tolerance) with every mode's residual accepted (at most
// 1e-8 or 20 times its rounding floor), or a refusal listed here with its reason. bench/cad_corpus_bench.py times
// the same runs.
namespace {

struct CorpusPart {
  std::string file;     ///< a FreeCAD model's name, "component8.step", or "as1-tu-203_solidKK.brep"
  std::string refusal;  ///< empty: a body file; else a piece of the one-line refusal
};

void PrintTo(const CorpusPart& part, std::ostream* out) { *out << part.file; }  // gtest's listing

const std::vector<CorpusPart>& corpus() {
  static const std::vector<CorpusPart> parts = [] {
    const std::string assembly = "an assembly is not one body";
    std::vector<CorpusPart> list = {
        {"0603_SMD.stp", ""}, {"0805_SMD.stp", ""}, {"1206_SMD.stp", ""}, {"1210_SMD.stp", ""}, {"1812_SMD.stp", ""},
        {"2225_SMD.stp", ""}, {"2512_SMD.stp", ""}, {"CAP_50SGV_8_10.stp", ""}, {"EPL22_6_16.stp", ""},
        {"I22_2_5_16.stp", ""}, {"I22_2_5_16withEPL22_6_16.stp", "found 2 disconnected solids; " + assembly},
        {"MSOP_10.stp", ""}, {"RLF_12545.igs", "sewn, they make 3 closed shells: " + assembly},
        {"RLF_12545.stp", "found 3 disconnected solids; " + assembly}, {"RLF_7030.stp", ""}, {"SMB_DO_214AA.stp", ""},
        {"SMC_DO_214AB.stp", ""}, {"SOD_323.igs", "sewing them made no closed solid: 34 free edges"},
        {"SOD_323.stp", "sewing them made no closed solid: 34 free edges"}, {"SOD_523.stp", ""}, {"SOT23.igs", ""},
        {"SOT23.stp", ""}, {"SOT404.igs", "sewing them made no closed solid: 12 free edges"},
        {"SOT404.stp", "found 4 disconnected solids; " + assembly}, {"SOT428_DPAK.stp", ""}, {"SOT_323_3.stp", ""},
        {"SOT_96.stp", ""}, {"TCMT1107_4.stp", ""}, {"TSM_103_01_L_DV_A.stp", ""}, {"TSM_104_01_L_DV_A.stp", ""},
        {"TSS0P_8.stp", ""}, {"VC0603_SMD.stp", ""}, {"component8.step", ""}};
    for (int k = 0; k < 18; ++k) list.push_back({fmt::format("as1-tu-203_solid{:02d}.brep", k), ""});
    return list;
  }();
  return parts;
}

const std::filesystem::path kGmshDemos = "/usr/share/doc/gmsh-doc/doc/gmsh/demos/boolean";

// The part's file, made in `dir` when it is one of gmsh's demos (gunzipped; an assembly's solid written alone).
std::filesystem::path part_file(const std::string& file, const std::filesystem::path& dir) {
  if (file == "component8.step" || file.rfind("as1-tu-203", 0) == 0) {
    const std::string source = file == "component8.step" ? "component8.step" : "as1-tu-203.stp";
    const auto unzipped = dir / source;
    if (std::system(fmt::format("gzip -dc '{}.gz' > '{}'", (kGmshDemos / source).string(), unzipped.string()).c_str()) != 0)
      throw std::runtime_error("cannot gunzip " + source);
    if (file == "component8.step") return unzipped;
    const int solid = std::stoi(file.substr(16, 2));
    gmsh::initialize();
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::model::add("assembly");
    gmsh::vectorpair volumes;
    gmsh::model::occ::importShapes(unzipped.string(), volumes);
    gmsh::vectorpair others;
    for (std::size_t k = 0; k < volumes.size(); ++k)
      if (static_cast<int>(k) != solid) others.push_back(volumes[k]);
    gmsh::model::occ::remove(others, /*recursive=*/true);
    gmsh::model::occ::synchronize();
    gmsh::write((dir / file).string());
    gmsh::finalize();
    return dir / file;
  }
  return kFreecadParts / file;
}

class CadCorpusPart : public ::testing::TestWithParam<std::tuple<CorpusPart, int>> {};

}  // namespace

TEST_P(CadCorpusPart, GivesABodyFileOrTheListedRefusal) {
  const auto& [part, order] = GetParam();
  const bool gmsh_demo = part.file == "component8.step" || part.file.rfind("as1-tu-203", 0) == 0;
  if (!std::filesystem::is_directory(gmsh_demo ? kGmshDemos : kFreecadParts))
    GTEST_SKIP() << (gmsh_demo ? kGmshDemos : kFreecadParts) << " is missing: scripts/setup.sh installs Debian's "
                 << (gmsh_demo ? "gmsh-doc" : "freecad-common");
  const auto dir = flexbody::test::scratch_dir();
  const std::filesystem::path input = part_file(part.file, dir);
  const bool brep = input.extension() == ".brep";
  const flexbody::test::CliRun run = flexbody::test::run_fbprep(
      dir, fmt::format("'{}' --order {} --json -o out.fbh5{}", input.string(), order, brep ? " --unit mm" : ""));
  if (!part.refusal.empty()) {
    EXPECT_NE(run.exit_code, 0);
    EXPECT_NE(run.err.find(part.refusal), std::string::npos) << run.err;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.fbh5"));
    return;
  }
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  ASSERT_TRUE(j["cad_volume_m3"].is_number());
  const double volume = j["mass_kg"].get<double>() / j["material"]["rho_kgm3"].get<double>();
  EXPECT_NEAR(volume / j["cad_volume_m3"].get<double>(), 1.0, 5e-3);
  EXPECT_TRUE(j["max_relative_residual"].get<double>() <= 1e-8 || j["max_residual_to_floor"].get<double>() <= 20.0);
  EXPECT_TRUE(std::filesystem::exists(dir / "out.fbh5"));
  if (order == 2) {
    EXPECT_TRUE(j["folded_elements"].is_object());
  }
}

INSTANTIATE_TEST_SUITE_P(
    Corpus, CadCorpusPart, ::testing::Combine(::testing::ValuesIn(corpus()), ::testing::Values(1, 2)),
    [](const ::testing::TestParamInfo<CadCorpusPart::ParamType>& param) {
      std::string name = std::get<0>(param.param).file + "_order" + std::to_string(std::get<1>(param.param));
      for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return name;
    });
