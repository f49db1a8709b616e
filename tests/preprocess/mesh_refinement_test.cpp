// The sizes of a mesh refined by the error estimate (mesh_refinement.hpp, issue 28 item 2), on shares made up to have
// known answers, then fbprep's default mesh refined end to end.
#include "flexbody/preprocess/fbprep_pipeline.hpp"
#include "flexbody/preprocess/mesh_refinement.hpp"
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace fp = flexbody::preprocess;

namespace {

fp::RefinementRequest request(int order, double target, double budget) {
  fp::RefinementRequest r;
  r.order = order;
  r.target_share = target;
  r.max_elements = budget;
  return r;
}

}  // namespace

// Equal shares: every element shrinks by the same s, with N σ s^(2p) = T, i.e. s = (T / (N σ))^(1/(2p)); here
// 100 elements of 0.01 each (total 1) to 0.25 with quadratic elements: s = 0.25^(1/4) = 0.7071, N / s³ = 282.8.
TEST(MeshRefinement, EqualSharesShrinkEveryElementAlike) {
  const Eigen::VectorXd sizes = Eigen::VectorXd::Constant(100, 2e-3), shares = Eigen::VectorXd::Constant(100, 0.01);
  const fp::RefinementPlan plan = fp::plan_refinement(sizes, shares, request(2, 0.25, 1e6));
  const double s = std::pow(0.25, 0.25);
  EXPECT_FALSE(plan.budget_bound);
  for (Eigen::Index e = 0; e < 100; ++e) EXPECT_NEAR(plan.sizes(e), s * 2e-3, 1e-9 * 2e-3);
  EXPECT_NEAR(plan.predicted_share, 0.25, 1e-9);
  EXPECT_NEAR(plan.predicted_elements, 100.0 / (s * s * s), 1e-6);
  // Linear elements converge as h² in the eigenvalue: s = 0.25^(1/2) = 0.5, eight times the elements.
  const fp::RefinementPlan linear = fp::plan_refinement(sizes, shares, request(1, 0.25, 1e6));
  EXPECT_NEAR(linear.sizes(0), 1e-3, 1e-12);
  EXPECT_NEAR(linear.predicted_elements, 800.0, 1e-6);
}

// Unequal shares: the refined elements end with equal η²_e s_e^(2p+3) (the fewest elements for the target:
// mesh_refinement.hpp), an element without error keeps its size, and none shrinks past `finest`.
TEST(MeshRefinement, TheErrorIsEquidistributedWithinTheBounds) {
  Eigen::VectorXd sizes(5), shares(5);
  sizes << 1.0, 2.0, 1.0, 1.0, 3.0;
  shares << 0.2, 0.05, 0.01, 0.0, 1e-6;
  fp::RefinementRequest r = request(2, 0.05, 1e6);
  r.finest = 0.1;
  const fp::RefinementPlan plan = fp::plan_refinement(sizes, shares, r);
  const Eigen::VectorXd s = plan.sizes.cwiseQuotient(sizes);
  EXPECT_NEAR(plan.predicted_share, 0.05, 1e-9);
  EXPECT_EQ(s(3), 1.0);  // no error: kept
  EXPECT_EQ(s(4), 1.0);  // so little that the equidistributed size would be coarser: kept (refine only)
  for (Eigen::Index e : {0, 1, 2}) {
    EXPECT_GT(s(e), 0.1);
    EXPECT_LT(s(e), 1.0);
    EXPECT_NEAR(shares(e) * std::pow(s(e), 7), shares(0) * std::pow(s(0), 7), 1e-9 * shares(0) * std::pow(s(0), 7));
  }
  double left = 0.0, elements = 0.0;
  for (Eigen::Index e = 0; e < 5; ++e) {
    left += shares(e) * std::pow(s(e), 4);
    elements += std::pow(s(e), -3);
  }
  EXPECT_NEAR(left, plan.predicted_share, 1e-12);
  EXPECT_NEAR(elements, plan.predicted_elements, 1e-9 * elements);
  // A target out of reach in one pass: every element with error at `finest` (0.1), the share left reported.
  r.target_share = 1e-9;
  const fp::RefinementPlan far = fp::plan_refinement(sizes, shares, r);
  for (Eigen::Index e : {0, 1, 2, 4}) EXPECT_NEAR(far.sizes(e), 0.1 * sizes(e), 1e-12);
  EXPECT_EQ(far.sizes(3), sizes(3));
  EXPECT_NEAR(far.predicted_share, 1e-4 * shares.sum(), 1e-15);
}

// The element budget wins over the target: Σ s_e^(-3) at most the budget (to the bisection's 1e-12), reported as
// bound; and a mesh that meets the target already is left as it is.
TEST(MeshRefinement, TheBudgetBoundsTheElements) {
  const Eigen::VectorXd sizes = Eigen::VectorXd::Constant(10, 1.0), shares = Eigen::VectorXd::LinSpaced(10, 0.01, 0.1);
  const fp::RefinementPlan free = fp::plan_refinement(sizes, shares, request(2, 0.01, 1e6));
  ASSERT_GT(free.predicted_elements, 40.0);
  const fp::RefinementPlan bound = fp::plan_refinement(sizes, shares, request(2, 0.01, 40.0));
  EXPECT_TRUE(bound.budget_bound);
  EXPECT_LE(bound.predicted_elements, 40.0 * (1.0 + 1e-9));
  EXPECT_GT(bound.predicted_elements, 40.0 * (1.0 - 1e-9));
  EXPECT_GT(bound.predicted_share, 0.01);
  const fp::RefinementPlan met = fp::plan_refinement(sizes, shares, request(2, 1.0, 10.0));
  EXPECT_EQ(met.sizes, sizes);
  EXPECT_EQ(met.predicted_elements, 10.0);
  EXPECT_FALSE(met.budget_bound);
}

TEST(MeshRefinement, BadRequestsAreRefused) {
  const Eigen::VectorXd sizes = Eigen::VectorXd::Ones(3), shares = Eigen::VectorXd::Constant(3, 0.1);
  EXPECT_THROW((void)fp::plan_refinement(sizes, Eigen::VectorXd::Ones(2), request(2, 0.1, 10)), std::invalid_argument);
  EXPECT_THROW((void)fp::plan_refinement(sizes, shares, request(3, 0.1, 10)), std::invalid_argument);
  EXPECT_THROW((void)fp::plan_refinement(sizes, shares, request(2, 0.0, 10)), std::invalid_argument);
  EXPECT_THROW((void)fp::plan_refinement(sizes, shares, request(2, 0.1, 2)), std::invalid_argument);
  Eigen::VectorXd bad = shares;
  bad(1) = std::nan("");
  EXPECT_THROW((void)fp::plan_refinement(sizes, bad, request(2, 0.1, 10)), std::invalid_argument);
  bad = sizes;
  bad(2) = 0.0;
  EXPECT_THROW((void)fp::plan_refinement(bad, shares, request(2, 0.1, 10)), std::invalid_argument);
}

// element_sizes: (8.5 V)^(1/3), gmsh's fill of a volume at size h (8.5 V / h³ tetrahedra; gmsh_import.cpp).
TEST(MeshRefinement, ElementSizesAreGmshsFill) {
  fp::TetMesh mesh;
  mesh.nodes.resize(4, 3);
  mesh.nodes << 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2;
  mesh.tets.resize(1, 4);
  mesh.tets << 0, 1, 2, 3;
  EXPECT_NEAR(fp::element_sizes(mesh)(0), std::cbrt(8.5 * 8.0 / 6.0), 1e-12);
}

// fbprep's default mesh, refined where the estimate puts the error (PrepOptions::error_target): a block 40 x 40 x 10 mm
// with a fin 1 mm thick and 10 mm tall on top, whose first modes bend the fin. The default size (2.4 mm) leaves the
// fin one element thick. Reference: quadratic tetrahedra at 0.8 mm, 654k DOFs, first frequency 8335 Hz (its own
// estimate 1.4 %).
// - Linear elements: the first mesh's 19.3 kHz (131 % high) is estimated only 13.9 % off (the estimate runs low where
//   a feature is one element thick), beyond the 5 % target: the fin is remeshed within the budget of 8 times the
//   tetrahedra (measured 6991 -> 49040, the plan 55928) and the first frequency falls to 10.8 kHz (30 % high; its
//   estimate, now 36 %, warns). Asserted: refined, within 1.25 x the budget, below 0.6 of the first mesh's and
//   within 40 % of the reference.
// - Quadratic elements (the default): 8560 Hz, estimated 4.4 %, within the target: not refined, 2.7 % above the
//   reference.
// - An explicit --mesh-size, or --error-target 0, keeps the first mesh.
TEST(MeshRefinement, TheDefaultMeshIsRefinedWhereTheEstimatePutsTheError) {
  const auto dir = flexbody::test::scratch_dir();
  flexbody::test::write_text(dir / "fin.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 0.04, 0.04, 0.01};\n"
                                              "Box(2) = {0, 0.0195, 0.01, 0.04, 0.001, 0.01};\n"
                                              "BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; }\n");
  constexpr double kReference = 8335.0;
  auto run = [&](const std::string& options) {
    const flexbody::test::CliRun r = flexbody::test::run_fbprep(dir, "fin.geo --unit m --json -o fin.fbh5 " + options);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out.empty() ? "{}" : r.out);
  };
  const nlohmann::json linear = run("--order 1");
  ASSERT_TRUE(linear.contains("mesh_refinement") && linear["mesh_refinement"].is_object()) << linear.dump();
  const nlohmann::json& refinement = linear["mesh_refinement"];
  const double first = refinement["first_frequency_hz"].get<double>(), refined = linear["frequencies_hz"][0].get<double>();
  EXPECT_GT(refinement["first_estimate"].get<double>(), 0.05);
  EXPECT_TRUE(refinement["budget_bound"].get<bool>());
  EXPECT_LE(linear["elements"].get<double>(), 1.25 * fp::kRefinementGrowth * refinement["first_elements"].get<double>());
  EXPECT_GT(linear["dofs"].get<double>(), 4.0 * refinement["first_dofs"].get<double>());
  EXPECT_GT(first, 2.0 * kReference);
  EXPECT_LT(refined, 0.6 * first);
  EXPECT_LT(refined, 1.4 * kReference);
  EXPECT_GT(refined, kReference);  // conforming elements: from above
  EXPECT_FALSE(linear["accuracy_warning"].is_null());  // still beyond 5 %: said so

  const nlohmann::json quadratic = run("");
  EXPECT_TRUE(quadratic["mesh_refinement"].is_null());
  EXPECT_NEAR(quadratic["frequencies_hz"][0].get<double>() / kReference, 1.027, 0.01);

  for (const std::string kept : {"--order 1 --error-target 0", "--order 1 --mesh-size 0.0024"}) {
    SCOPED_TRACE(kept);
    const nlohmann::json j = run(kept);
    EXPECT_TRUE(j["mesh_refinement"].is_null());
    EXPECT_NEAR(j["frequencies_hz"][0].get<double>(), first, 0.02 * first);
  }
}

// The library's own checks: an error target outside [0, 1) is refused before any work, and a plan that refines
// nothing (a budget no larger than the first mesh: GmshImportOptions::volume_search_elements at 1) keeps the first
// mesh instead of meshing the part again for nothing.
TEST(MeshRefinement, ALibraryRunRefusesBadTargetsAndSkipsEmptyPlans) {
  const auto dir = flexbody::test::scratch_dir();
  flexbody::test::write_text(dir / "fin.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 0.04, 0.04, 0.01};\n"
                                              "Box(2) = {0, 0.0195, 0.01, 0.04, 0.001, 0.01};\n"
                                              "BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; }\n");
  fp::PrepOptions options;
  options.input = dir / "fin.geo";
  options.output = dir / "fin.fbh5";
  options.mesh.unit = fp::LengthUnit::metre;
  options.mesh.order = 1;
  options.modes.modes = 2;
  for (const double bad : {1.0, -0.1, std::nan("")}) {
    options.error_target = bad;
    EXPECT_THROW((void)fp::run_fbprep(options), std::invalid_argument) << bad;
  }
  EXPECT_FALSE(std::filesystem::exists(options.output));
  options.error_target = fp::kDefaultErrorTarget;
  options.mesh.volume_search_elements = 1.0;
  const fp::PrepSummary kept = fp::run_fbprep(options);
  EXPECT_FALSE(kept.refinement.has_value());
  EXPECT_GT(kept.frequency_errors(0), 0.05);  // the first mesh's 13.9 %, kept and warned about
  EXPECT_TRUE(std::filesystem::exists(options.output));
}
