// The initial assembly (issue 27): a scene whose joints' markers are a few micrometres apart, as interfaces taken
// from meshes are, is closed by the least mass-weighted move of the bodies and then runs; a gap of a tenth of a body
// is a modelling error and is refused with one line naming a joint.
#include "flexbody/runtime/assembly.hpp"
#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "test_bodies.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace fr = flexbody::runtime;

namespace {

// A soft bar 0.5 x 0.04 x 0.02 m (E 5e9 Pa, ρ 1000 kg/m³), its first 3 free-free modes.
const flexbody::format::BodyData& bar() {
  static const flexbody::format::BodyData data = flexbody::test::soft_bar(0.5, 6, 3);
  return data;
}

// Four bars (GCMS, FFRF, rigid, GCMS) in a row along x, 0.5 m apart, hanging from revolute joints about z between
// their ends (point markers), each joint's second marker `gap` metres off the first along y.
std::unique_ptr<fr::System> chain(double gap) {
  auto system = std::make_unique<fr::System>();
  for (int k = 0; k < 4; ++k) {
    fr::BodyModel model = fr::make_body_model(bar(), std::nullopt, "bar");
    if (k == 1) model.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(model, fr::FloatingFrame::mean_axis));
    if (k == 2) model = fr::rigid_body_model(model.mass, model.mass_matrix.block<3, 3>(1, 1), "box");
    fr::BodyState state;
    state.position = Eigen::Vector3d(0.5 * k, 0.0, 0.0);
    std::string name = "b";
    name += std::to_string(k);
    system->add_body(name, std::move(model), state);
  }
  const Eigen::VectorXd q0 = system->initial_coordinates();
  const Eigen::Vector3d end(-0.25, 0.0, 0.0), off(0.0, gap, 0.0);
  for (int k = 0; k < 4; ++k) {
    const fr::Marker first = fr::point_marker(system->model(k), k, system->body_name(k), end);
    const Eigen::Vector3d at = q0.segment<3>(system->offset(k)) + end + off;
    const fr::Marker second = k == 0 ? fr::ground_marker(at)
                                     : fr::point_marker(system->model(k - 1), k - 1, system->body_name(k - 1), -end + off);
    std::string name = "j";
    name += std::to_string(k);
    system->add_joint(fr::make_joint(name, fr::JointType::revolute, first, second, Eigen::Vector3d::UnitZ(),
                                     system->body_coordinates(q0, k),
                                     k == 0 ? Eigen::VectorXd() : system->body_coordinates(q0, k - 1)));
  }
  system->set_gravity(Eigen::Vector3d(0, -9.81, 0));
  return system;
}

}  // namespace

TEST(Assembly, FiveMicrometreGapsCloseAndTheSceneRuns) {
  const auto system = chain(5e-6);
  EXPECT_THROW(fr::GeneralizedAlpha(*system, fr::GeneralizedAlphaOptions{}), std::invalid_argument);  // not assembled
  const fr::AssemblyReport report = fr::assemble(*system);
  EXPECT_GE(report.iterations, 1);
  EXPECT_NEAR(report.largest_gap, 5e-6, 1e-9);
  // Every joint closes to the rounding of its positions (~1 m: 64 ε), the bodies stay rigid.
  const Eigen::VectorXd q = system->initial_coordinates();
  EXPECT_LT(system->constraints(0.0, q).cwiseAbs().maxCoeff(), 1e-13);
  // The least mass-weighted move spreads the four 5 µm gaps over the chain (measured: 2.7 to 6.7 µm per body, the
  // most for the body hung from ground); every body moves, and none by more than the gaps add up to, with the
  // lever of a turn (x 1.5).
  ASSERT_EQ(report.moves.size(), 4u);
  for (double move : report.moves) {
    EXPECT_GT(move, 1e-6);
    EXPECT_LT(move, 4 * 5e-6 * 1.5);
  }
  fr::GeneralizedAlpha integrator(*system, fr::GeneralizedAlphaOptions{});
  for (int s = 0; s < 10; ++s) integrator.step();
  EXPECT_LT(system->constraints(integrator.time(), integrator.coordinates()).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(Assembly, ATenthOfABodyIsRefusedNamingAJoint) {
  const auto system = chain(0.05);  // a tenth of the 0.5 m bar
  try {
    fr::assemble(*system);
    ADD_FAILURE() << "a 5 cm gap was closed";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("joint 'j", 0), 0u) << what;
    EXPECT_NE(what.find("more than the assembly tolerance (1 % of its size"), std::string::npos) << what;
  }
  // With a tolerance of 30 %, the same scene assembles.
  fr::AssemblyOptions loose;
  loose.tolerance = 0.3;
  EXPECT_NO_THROW(fr::assemble(*system, loose));
}
