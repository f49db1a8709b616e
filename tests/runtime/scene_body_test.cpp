// A body from its body file by a SceneBody (issue 31: fbsim's body keys for scenes in code): the builder's model is the
// one the lower-level calls make, each file is read once, and every refusal names its key.
#include "flexbody/format/body_file.hpp"
#include "flexbody/runtime/damping.hpp"
#include "flexbody/runtime/scene_builder.hpp"
#include "test_bodies.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>
#include <utility>

namespace fr = flexbody::runtime;

namespace {

// The soft bar's body file (10 free-free modes), written once.
const std::filesystem::path& bar_file() {
  static const std::filesystem::path path = [] {
    const std::filesystem::path p = flexbody::test::scratch_dir() / "soft_bar.fbh5";
    flexbody::format::BodyData bar = flexbody::test::soft_bar(0.5, 6, 10);
    bar.material = {"custom", 5e9, 0.3, 1000.0};  // soft_bar's (a body file must name its material)
    flexbody::format::write_body_file(bar, p);
    return p;
  }();
  return path;
}

// A spec of the bar's file with `modes` (none: all), changed by `edit`.
template <class Edit>
fr::SceneBody spec_of(std::optional<Eigen::Index> modes, Edit edit) {
  fr::SceneBody spec;
  spec.file = bar_file();
  spec.modes = modes;
  edit(spec);
  return spec;
}
fr::SceneBody spec_of(std::optional<Eigen::Index> modes) {
  return spec_of(modes, [](fr::SceneBody&) {});
}

// The key of the SceneError that adding `spec` throws, and its message.
std::pair<std::string, std::string> refusal(const fr::SceneBody& spec) {
  fr::System system;
  fr::SceneBuilder scene(system);
  try {
    scene.add_body("bar", spec);
  } catch (const fr::SceneError& e) {
    return {e.key(), e.what()};
  }
  return {"", "accepted"};
}

}  // namespace

TEST(SceneBody, MakesTheModelTheLowerLevelCallsMake) {
  const flexbody::format::BodyData data = flexbody::format::read_body_file(bar_file());
  fr::System system;
  fr::SceneBuilder scene(system);
  fr::SceneBody spec = spec_of(4);
  spec.damping.emplace().modal = 0.02;
  spec.damping->beta = 1e-5;
  fr::Placement placement;
  placement.position = Eigen::Vector3d(1.0, 2.0, 3.0);
  const int b = scene.add_body("bar", spec, placement);
  fr::BodyModel by_hand = fr::make_body_model(data, 4, "soft_bar.fbh5");
  by_hand.damping =
      fr::rayleigh_damping(by_hand, 0.0, 1e-5) + fr::modal_damping(by_hand, Eigen::VectorXd::Constant(4, 0.02));
  const fr::BodyModel& built = system.model(b);
  EXPECT_EQ(built.modes, 4);
  EXPECT_FALSE(built.floating());
  EXPECT_TRUE(built.damping == by_hand.damping);  // the same sums, bit for bit
  EXPECT_TRUE(built.stiffness == by_hand.stiffness);
  // Placed by the input frame: the centre of mass where the placement puts the file's input-frame one.
  const Eigen::VectorXd q_b = system.initial_body_coordinates(b);
  EXPECT_LT((q_b.head<3>() - (placement.position + data.mass.center_of_mass_input)).norm(), 1e-15);

  // Rigid: 7 floating-frame coordinates by default, the GCMS's 12 when asked.
  const int rigid = scene.add_body("rigid", spec_of(0));
  EXPECT_TRUE(system.model(rigid).floating());
  EXPECT_EQ(system.model(rigid).modes, 0);
  const int gcms = scene.add_body(
      "rigid_gcms", spec_of(0, [](fr::SceneBody& s) { s.formulation = fr::SceneBody::Formulation::gcms; }));
  EXPECT_FALSE(system.model(gcms).floating());
  const int ffrf =
      scene.add_body("ffrf", spec_of(3, [](fr::SceneBody& s) { s.formulation = fr::SceneBody::Formulation::ffrf; }));
  EXPECT_TRUE(system.model(ffrf).floating());
  EXPECT_EQ(system.model(ffrf).modes, 3);
}

TEST(SceneBody, EachFileIsReadOncePerBuilder) {
  const std::filesystem::path copy = bar_file().parent_path() / "read_once.fbh5";
  std::filesystem::copy_file(bar_file(), copy, std::filesystem::copy_options::overwrite_existing);
  fr::System system;
  fr::SceneBuilder scene(system);
  scene.add_body("first", spec_of(std::nullopt, [&](fr::SceneBody& s) { s.file = copy; }));
  std::filesystem::remove(copy);  // the second body of the same file comes from the builder's copy
  EXPECT_NO_THROW(scene.add_body("second", spec_of(std::nullopt, [&](fr::SceneBody& s) { s.file = copy; })));
  EXPECT_EQ(system.model(1).modes, 10);
  fr::System other;
  fr::SceneBuilder fresh(other);
  EXPECT_THROW(fresh.add_body("first", spec_of(std::nullopt, [&](fr::SceneBody& s) { s.file = copy; })),
               fr::SceneError);
}

TEST(SceneBody, EveryRefusalNamesItsKey) {
  using F = fr::SceneBody::Formulation;
  EXPECT_EQ(refusal(spec_of(std::nullopt, [](fr::SceneBody& s) { s.file = s.file.parent_path() / "none.fbh5"; })).first,
            "file");
  EXPECT_EQ(refusal(spec_of(11)).first, "modes");  // the file holds 10
  EXPECT_EQ(refusal(spec_of(3, [](fr::SceneBody& s) { s.full = true; })).first, "modes");
  EXPECT_EQ(refusal(spec_of(std::nullopt,
                            [](fr::SceneBody& s) {
                              s.full = true;
                              s.formulation = F::ffrf;
                            }))
                .first,
            "formulation");
  EXPECT_EQ(refusal(spec_of(std::nullopt, [](fr::SceneBody& s) { s.frame = fr::FloatingFrame::mean_axis; })).first,
            "frame");
  const auto hub = refusal(spec_of(std::nullopt, [](fr::SceneBody& s) {
    s.formulation = F::ffrf;
    s.frame = fr::FloatingFrame::interface;
    s.frame_interface = "hub";
  }));
  EXPECT_EQ(hub.first, "frame");
  EXPECT_NE(hub.second.find("body 'bar' frame: soft_bar.fbh5: no interface 'hub'"), std::string::npos) << hub.second;
  const auto ratios =
      refusal(spec_of(4, [](fr::SceneBody& s) { s.damping.emplace().modal_ratios = Eigen::VectorXd::Zero(3); }));
  EXPECT_EQ(ratios,
            std::make_pair(std::string("damping"), std::string("body 'bar' damping modal lists 3 ratios for 4 modes")));
  EXPECT_EQ(refusal(spec_of(std::nullopt, [](fr::SceneBody& s) { s.damping.emplace().modal = 1.5; })).first,
            "damping");  // ζ > 1
  EXPECT_EQ(refusal(spec_of(std::nullopt,
                            [](fr::SceneBody& s) {
                              s.full = true;
                              s.damping.emplace().modal = 0.01;
                            }))
                .first,
            "damping");
  EXPECT_EQ(refusal(spec_of(std::nullopt, [](fr::SceneBody& s) { s.geometric_stiffness = true; })).first,
            "geometric_stiffness");  // the file holds none
  EXPECT_EQ(refusal(spec_of(0, [](fr::SceneBody& s) { s.geometric_stiffness = true; })).first, "geometric_stiffness");
  EXPECT_EQ(refusal(spec_of(4, [](fr::SceneBody& s) { s.geometric_stiffness = false; })).first,
            "");  // off: always allowed
}
