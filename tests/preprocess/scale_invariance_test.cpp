// Issue 12: the same part at 1 mm and at 100 m. fbprep must write a body file its own reader accepts at
// every size, the physics must scale exactly (frequencies like 1/L, mass like L³ for the same mesh scaled),
// and the conditioning figures must not depend on the size.
#include "flexbody/format/body_file.hpp"
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <map>

namespace {

// The mesh as a gmsh MSH 2.2 file with every coordinate multiplied by `scale` (one rounding each, printed
// to 17 digits so that it reads back exactly): the same topology at every size.
void write_scaled_msh(const flexbody::preprocess::TetMesh& mesh, double scale, const std::filesystem::path& path) {
  std::ofstream out(path);
  out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << mesh.node_count() << '\n';
  for (Eigen::Index i = 0; i < mesh.node_count(); ++i)
    out << fmt::format("{} {:.17g} {:.17g} {:.17g}\n", i + 1, scale * mesh.nodes(i, 0), scale * mesh.nodes(i, 1),
                       scale * mesh.nodes(i, 2));
  out << "$EndNodes\n$Elements\n" << mesh.element_count() << '\n';
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e)
    out << fmt::format("{} 4 2 1 1 {} {} {} {}\n", e + 1, mesh.tets(e, 0) + 1, mesh.tets(e, 1) + 1, mesh.tets(e, 2) + 1,
                       mesh.tets(e, 3) + 1);
  out << "$EndElements\n";
}

double relative(double value, double reference) { return std::abs(value - reference) / std::abs(reference); }

}  // namespace

// The box beam of the issue (1 x 0.05 x 0.05, steel, free-free) at 1 mm, 1 m and 100 m: one structured mesh
// (20 x 2 x 2 cells, 189 nodes) written at each size, 6 modes.
TEST(ScaleInvariance, BoxBeamFromOneMillimetreToOneHundredMetres) {
  const auto dir = flexbody::test::scratch_dir();
  const flexbody::preprocess::TetMesh mesh = flexbody::test::box_mesh(1.0, 0.05, 0.05, 20, 2, 2);
  std::map<double, nlohmann::json> runs;
  for (const double s : {1e-3, 1.0, 1e2}) {
    SCOPED_TRACE(fmt::format("{} m", s));
    const std::string name = fmt::format("beam-{:g}", s);
    write_scaled_msh(mesh, s, dir / (name + ".msh"));
    // Before issue 12 the 1 mm beam failed here: "body data: /gcms/condition_G_after is inf, expected a finite
    // number" (G's λmin, in kg m², fell below the round-off of its identity block).
    const flexbody::test::CliRun run = flexbody::test::run_fbprep(
        dir, fmt::format("{0}.msh --unit m --material steel --modes 6 --json -o {0}.fbh5", name));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    ASSERT_NO_THROW((void)flexbody::format::read_body_file(dir / (name + ".fbh5")));
    const auto json = nlohmann::json::parse(run.out);
    EXPECT_EQ(json["nodes"].get<long>(), mesh.node_count());
    // Every figure is a number (null would be a singular matrix), the SI ones included: fbprep computes λmin
    // of G through its Jacobi scaling, so they stay finite however far the units push G's blocks apart.
    for (const char* key : {"condition_mode_gram_before", "condition_G_before", "condition_G_after",
                            "condition_G_scaled_before", "condition_G_scaled_after"}) {
      ASSERT_TRUE(json[key].is_number()) << key << ": " << json[key];
      EXPECT_GE(json[key].get<double>(), 1.0) << key;
    }
    runs[s] = json;
  }
  const nlohmann::json& metre = runs[1.0];
  for (const double s : {1e-3, 1e2}) {
    SCOPED_TRACE(fmt::format("{} m against 1 m", s));
    const nlohmann::json& run = runs[s];
    // Mass like L³: the consistent mass sums ρ V_e, exact up to the rounding of the scaled coordinates
    // (a few eps relative; measured 5e-16 and 9e-16).
    EXPECT_LT(relative(run["mass_kg"].get<double>() / (s * s * s), metre["mass_kg"].get<double>()), 1e-13);
    // Frequencies like 1/L: K̄ scales by s, M̄ by s³, so ω² by s⁻² exactly; what remains is the eigensolver's
    // accuracy on each problem (relative residuals ~1e-11, which bound the eigenvalue error by about their
    // square times ||K̄||/gap) and the rounded coordinates. Measured 9e-13 at most.
    const auto& f = run["frequencies_hz"];
    const auto& f_metre = metre["frequencies_hz"];
    ASSERT_EQ(f.size(), f_metre.size());
    for (std::size_t k = 0; k < f.size(); ++k)
      EXPECT_LT(relative(f[k].get<double>() * s, f_metre[k].get<double>()), 1e-10) << "mode " << k;
    // The unit-free conditioning figures are the same: the Jacobi-scaled G (and the Gram matrix of the
    // M-orthonormal modes) is the same matrix at every size up to round-off δ in its entries, and a condition
    // number κ moves by about κ δ relative. δ is the agreement of the two computations (the modes' signs and
    // the order of round-off differ), a few eps: allowing δ = 1e-14 gives κ 1e-14. On this mesh κ is 3.3e3
    // (G after), 8.5e9 (the Gram matrix and G before: the structured mesh's bending pairs are close), and the
    // measured differences are κ times 2.6e-15 at most (8.5e-12 and 3.5e-6 relative).
    for (const char* key : {"condition_mode_gram_before", "condition_G_scaled_before", "condition_G_scaled_after"}) {
      const double kappa = metre[key].get<double>();
      EXPECT_LT(relative(run[key].get<double>(), kappa), 1e-14 * kappa) << key;
    }
    EXPECT_EQ(run["gcms_fields"], metre["gcms_fields"]);
  }
}
