// The System's C++ API as a simulator uses it: references it hands out stay valid while bodies are added.
#include "flexbody/runtime/system.hpp"

#include <gtest/gtest.h>

#include <string>

namespace fr = flexbody::runtime;

namespace {

// A rigid unit cube of 1 kg: G = diag(m, J) with J = ∫ x xᵀ dm = m/12 I.
fr::BodyModel rigid_cube() {
  fr::BodyModel model;
  model.source = "cube";
  model.mass = 1.0;
  model.mass_matrix = Eigen::Matrix4d::Identity() / 12.0;
  model.mass_matrix(0, 0) = 1.0;
  model.stiffness.resize(0, 0);
  model.tisserand.resize(3, 0);
  model.nodes = flexbody::format::RowMatrixX3d::Zero(2, 3);
  model.nodes(1, 0) = 1.0;
  return model;
}

}  // namespace

// Issue 12, item 9: System::model(b) returned a reference into a std::vector that reallocated on the next add_body,
// so a simulator keeping it read freed memory. The bodies now live in a deque, which never moves its elements.
TEST(System, ModelReferencesSurviveAddingBodies) {
  fr::System system;
  system.add_body("first", rigid_cube(), fr::BodyState{});
  const fr::BodyModel& kept = system.model(0);
  const std::string& kept_name = system.body_name(0);
  for (int k = 1; k < 200; ++k) system.add_body("body" + std::to_string(k), rigid_cube(), fr::BodyState{});
  EXPECT_EQ(&kept, &system.model(0));
  EXPECT_EQ(&kept_name, &system.body_name(0));
  EXPECT_EQ(kept.nodes.rows(), 2);  // read through the kept reference (AddressSanitizer would flag freed memory)
  EXPECT_EQ(kept.source, "cube");
  EXPECT_EQ(kept_name, "first");
}
