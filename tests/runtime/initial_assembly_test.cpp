// The initial assembly (issue 27): a scene whose joints' markers are a few micrometres apart, as interfaces taken
// from meshes are, is closed by the least mass-weighted move of the bodies and then runs; a gap of a tenth of a body
// is a modelling error and is refused with one line naming a joint.
#include "flexbody/runtime/initial_assembly.hpp"
#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "test_bodies.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace fr = flexbody::runtime;

namespace {

// A soft bar 0.5 x 0.04 x 0.02 m (E 5e9 Pa, ρ 1000 kg/m³), its first 10 free-free modes (enough to bend and twist
// out of a plane).
const flexbody::format::BodyData& bar() {
  static const flexbody::format::BodyData data = flexbody::test::soft_bar(0.5, 6, 10);
  return data;
}

// Four bars (GCMS, FFRF, rigid, GCMS) in a row along x, 0.5 m apart, hanging from revolute joints about z between
// their ends (point markers), each joint's second marker `gap` metres off the first along y.
std::unique_ptr<fr::System> chain(double gap) {
  auto system = std::make_unique<fr::System>();
  for (int k = 0; k < 4; ++k) {
    fr::BodyModel model = fr::make_body_model(bar(), std::nullopt, "bar");
    if (k == 1)
      model.floating_frame =
          std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(model, fr::FloatingFrame::mean_axis));
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
    const fr::Marker second = k == 0
                                  ? fr::ground_marker(at)
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

TEST(InitialAssembly, FiveMicrometreGapsCloseAndTheSceneRuns) {
  const auto system = chain(5e-6);
  EXPECT_THROW(fr::GeneralizedAlpha(*system, fr::GeneralizedAlphaOptions{}), std::invalid_argument);  // not assembled
  const fr::InitialAssemblyReport report = fr::initial_assembly(*system);
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
  // An open chain closes by rigid moves alone: no body is deformed (bit for bit: their ξ turn with them).
  for (double d : report.deformations) EXPECT_EQ(d, 0.0);
  EXPECT_EQ(report.strain_energy, 0.0);
}

TEST(InitialAssembly, ATenthOfABodyIsRefusedNamingAJoint) {
  const auto system = chain(0.05);  // a tenth of the 0.5 m bar
  try {
    fr::initial_assembly(*system);
    ADD_FAILURE() << "a 5 cm gap was closed";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("joint 'j", 0), 0u) << what;
    EXPECT_NE(what.find("more than the assembly tolerance (1 % of its size"), std::string::npos) << what;
  }
  // With a tolerance of 30 %, the same scene assembles.
  fr::InitialAssemblyOptions loose;
  loose.tolerance = 0.3;
  EXPECT_NO_THROW(fr::initial_assembly(*system, loose));
}

namespace {

enum class Coupler { gcms, ffrf, rigid };

// A parallelogram four-bar in the xy plane, revolute joints about z: a crank from the ground pivot (0, 0) up to
// (0, 0.5), a coupler across to (0.5, 0.5), a rocker down to the ground pivot (0.5, 0); the crank and the rocker are
// rigid, the coupler is a bar of `coupler` kind, pinned at the nodes of its ends' lower edges (z = −0.01 m), which
// move with its deformation (a rigid coupler at those points). The last joint's ground marker is `gap` off.
std::unique_ptr<fr::System> four_bar(Coupler coupler, const Eigen::Vector3d& gap) {
  auto system = std::make_unique<fr::System>();
  const fr::BodyModel flexible = fr::make_body_model(bar(), std::nullopt, "bar");
  const fr::BodyModel link = fr::rigid_body_model(flexible.mass, flexible.mass_matrix.block<3, 3>(1, 1), "link");
  const Eigen::Matrix3d upright = Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  fr::BodyState crank, middle, rocker;
  crank.position = Eigen::Vector3d(0.0, 0.25, 0.0);
  crank.orientation = upright;
  middle.position = Eigen::Vector3d(0.25, 0.5, 0.0);
  rocker.position = Eigen::Vector3d(0.5, 0.25, 0.0);
  rocker.orientation = upright;
  system->add_body("crank", link, crank);
  fr::BodyModel model = coupler == Coupler::rigid ? link : flexible;
  if (coupler == Coupler::ffrf)
    model.floating_frame =
        std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(model, fr::FloatingFrame::mean_axis));
  system->add_body("coupler", std::move(model), middle);
  system->add_body("rocker", link, rocker);
  const Eigen::VectorXd q0 = system->initial_coordinates();
  const Eigen::Vector3d low(-0.25, 0.0, 0.0), high(0.25, 0.0, -0.01);  // a link's ends in its own axes
  auto at = [&](int body, const Eigen::Vector3d& end) {
    const fr::BodyModel& on = system->model(body);
    if (body != 1) return fr::point_marker(on, body, system->body_name(body), end);
    const Eigen::Vector3d edge(end.x(), 0.0, -0.01);
    if (on.nodes.rows() == 0) return fr::point_marker(on, body, system->body_name(body), edge);
    Eigen::Index node = 0;
    (on.nodes.rowwise() - edge.transpose()).rowwise().squaredNorm().minCoeff(&node);
    return fr::node_marker(on, body, system->body_name(body), node);
  };
  auto join = [&](const std::string& name, const fr::Marker& first, const fr::Marker& second) {
    const Eigen::VectorXd q2 =
        second.body == fr::kGround ? Eigen::VectorXd() : system->body_coordinates(q0, second.body);
    system->add_joint(fr::make_joint(name, fr::JointType::revolute, first, second, Eigen::Vector3d::UnitZ(),
                                     system->body_coordinates(q0, first.body), q2));
  };
  join("ground_crank", at(0, low), fr::ground_marker(Eigen::Vector3d::Zero()));
  join("crank_coupler", at(1, low), at(0, high));
  join("coupler_rocker", at(2, high), at(1, high));
  join("rocker_ground", at(2, low), fr::ground_marker(Eigen::Vector3d(0.5, 0.0, 0.0) + gap));
  system->set_gravity(Eigen::Vector3d(0, -9.81, 0));
  return system;
}

}  // namespace

// A planar loop of revolute joints repeats three rows among rigid coordinates; with a flexible coupler the rows are
// independent (it can bend out of its plane), so no row is removed, and a gap normal to the plane is closed by
// bending the coupler, the least strain energy, where rigid moves cannot close it.
TEST(InitialAssembly, AGapNormalToAPlanarLoopBendsItsFlexibleCoupler) {
  for (const Coupler kind : {Coupler::gcms, Coupler::ffrf}) {
    SCOPED_TRACE(kind == Coupler::gcms ? "gcms" : "ffrf");
    const auto system = four_bar(kind, Eigen::Vector3d(0.0, 0.0, 5e-6));
    // The coupler's pins are nodes, whose frames are the body's: only the last joint's two tilts repeat the others'
    // (the translation along z is independent through the coupler's bending).
    const std::vector<fr::RemovedConstraint> removed =
        system->remove_redundant_constraints(0.0, system->initial_coordinates());
    ASSERT_EQ(removed.size(), 2u);
    EXPECT_EQ(removed[0].row, 3);
    EXPECT_EQ(removed[1].row, 4);
    const fr::InitialAssemblyReport report = fr::initial_assembly(*system);
    const Eigen::VectorXd q = system->initial_coordinates();
    EXPECT_LT(system->constraints(0.0, q).cwiseAbs().maxCoeff(), 1e-13);
    ASSERT_EQ(report.deformations.size(), 3u);
    EXPECT_EQ(report.deformations[0], 0.0);  // the rigid links
    EXPECT_EQ(report.deformations[2], 0.0);
    // The rocker rises by the gap (measured 5.2 µm with its turn), the coupler's ends part by it along z, and its
    // mean-axis frame must stay parallel to the links (the pins' axes): its nodes move by about half the gap each way
    // (measured 2.58 µm GCMS, 2.61 µm FFRF).
    EXPECT_GT(report.deformations[1], 0.4 * 5e-6);
    EXPECT_LT(report.deformations[1], 0.6 * 5e-6);
    EXPECT_NEAR(report.moves[2], 5e-6, 0.5e-6);
    // A linear body's least strain energy for a misfit grows with its square (to the ε-share of the rigid moves).
    const auto twice = four_bar(kind, Eigen::Vector3d(0.0, 0.0, 10e-6));
    (void)twice->remove_redundant_constraints(0.0, twice->initial_coordinates());
    EXPECT_NEAR(fr::initial_assembly(*twice).strain_energy / report.strain_energy, 4.0, 1e-4);
    fr::GeneralizedAlpha integrator(*system, fr::GeneralizedAlphaOptions{});
    for (int s = 0; s < 10; ++s) integrator.step();
    EXPECT_LT(system->constraints(integrator.time(), integrator.coordinates()).cwiseAbs().maxCoeff(), 1e-10);
  }
}

// A gap in the plane closes by rigid moves; the coupler's deformation takes a share of order ε = 1e-6 of it.
TEST(InitialAssembly, AGapInThePlaneOfAFlexibleLoopClosesRigidly) {
  for (const Coupler kind : {Coupler::gcms, Coupler::ffrf}) {
    SCOPED_TRACE(kind == Coupler::gcms ? "gcms" : "ffrf");
    const auto system = four_bar(kind, Eigen::Vector3d(0.0, 5e-6, 0.0));
    (void)system->remove_redundant_constraints(0.0, system->initial_coordinates());
    const fr::InitialAssemblyReport report = fr::initial_assembly(*system);
    EXPECT_LT(system->constraints(0.0, system->initial_coordinates()).cwiseAbs().maxCoeff(), 1e-13);
    EXPECT_GT(report.moves[1], 1e-6);
    EXPECT_LT(report.deformations[1], 1e-5 * report.moves[1]);  // measured 1.6e-6 (GCMS)
  }
}

// Only bodies on a loop may deform: a flexible pendulum hung from ground beside a rigid four-bar, 5 µm off its pivot,
// moves rigidly (its deformation exactly zero, its ξ turned with it) while the loop's gap closes.
TEST(InitialAssembly, AFlexibleBodyOffTheLoopMovesRigidly) {
  const auto system = four_bar(Coupler::rigid, Eigen::Vector3d(0.0, 0.0, 0.0));
  fr::BodyState hanging;
  hanging.position = Eigen::Vector3d(2.0, -0.25, 0.0);
  hanging.orientation = Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const int pendulum = system->add_body("pendulum", fr::make_body_model(bar(), std::nullopt, "bar"), hanging);
  const Eigen::VectorXd q0 = system->initial_coordinates();
  const fr::Marker top =
      fr::point_marker(system->model(pendulum), pendulum, "pendulum", Eigen::Vector3d(0.25, 0.0, 0.0));
  system->add_joint(fr::make_joint("hang", fr::JointType::spherical, top,
                                   fr::ground_marker(Eigen::Vector3d(2.0, 5e-6, 0.0)), Eigen::Vector3d::UnitZ(),
                                   system->body_coordinates(q0, pendulum), Eigen::VectorXd()));
  (void)system->remove_redundant_constraints(0.0, q0);
  const fr::InitialAssemblyReport report = fr::initial_assembly(*system);
  EXPECT_LT(system->constraints(0.0, system->initial_coordinates()).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_GT(report.moves[3], 1e-6);
  EXPECT_EQ(report.deformations[3], 0.0);
  EXPECT_EQ(report.strain_energy, 0.0);
}
