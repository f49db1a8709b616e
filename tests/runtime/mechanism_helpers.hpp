#pragma once
// mechanism_helpers.hpp: mechanisms of many bodies for the runtime's tests: random open trees and closed loops (every
// joint type, GCMS, FFRF and rigid bodies, springs) and chains.
#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/system.hpp"
#include "test_bodies.hpp"

#include <Eigen/Geometry>

#include <memory>
#include <optional>
#include <random>
#include <string>
#include <utility>

namespace mechanisms {

namespace fr = flexbody::runtime;

// prefix + k (not "b" + std::to_string(k): GCC 12's -Wrestrict misfires on that at -O3).
inline std::string numbered(const char* prefix, int k) {
  std::string name = prefix;
  name += std::to_string(k);
  return name;
}

// A soft bar 0.5 x 0.04 x 0.02 m (E 5e9 Pa, ρ 1000 kg/m³; 6 x 2 x 1 Kuhn-split cells), its first 3 free-free modes.
inline const flexbody::format::BodyData& bar() {
  static const flexbody::format::BodyData data = flexbody::test::soft_bar(0.5, 6, 3);
  return data;
}

enum class Kind { rigid, gcms, ffrf };

inline fr::BodyModel model_of(Kind kind) {
  if (kind == Kind::rigid) return fr::rigid_body_model(0.4, Eigen::Vector3d(2e-3, 1e-3, 5e-4).asDiagonal(), "box");
  fr::BodyModel model = fr::make_body_model(bar(), std::nullopt, "bar");
  if (kind == Kind::ffrf)
    model.floating_frame = std::make_shared<const fr::FfrfModel>(fr::make_ffrf_model(model, fr::FloatingFrame::mean_axis));
  return model;
}

// A marker on body b near the world point p, and the world point it is at: a mesh node (whose position follows the
// deformation) on a flexible body, the point itself on a rigid one.
inline std::pair<fr::Marker, Eigen::Vector3d> marker_near(const fr::System& system, const Eigen::VectorXd& q0, int b,
                                                   const Eigen::Vector3d& p) {
  const fr::BodyModel& model = system.model(b);
  const Eigen::VectorXd q_b = system.body_coordinates(q0, b);
  const Eigen::Matrix3d a = system.orientation(b, q0);
  const Eigen::Vector3d local = a.transpose() * (p - q_b.head<3>());
  if (model.rigid()) return {fr::point_marker(model, b, system.body_name(b), local), p};
  Eigen::Index node = 0;
  (model.nodes.rowwise() - local.transpose()).rowwise().squaredNorm().minCoeff(&node);
  const fr::Marker m = fr::node_marker(model, b, system.body_name(b), node);
  return {m, fr::marker_position(m, q_b)};
}

// The other side of a joint at the world point p: a point fixed on body b (or on ground).
inline fr::Marker point_on(const fr::System& system, const Eigen::VectorXd& q0, int b, const Eigen::Vector3d& p) {
  if (b == fr::kGround) return fr::ground_marker(p);
  const Eigen::Vector3d local = system.orientation(b, q0).transpose() * (p - q0.segment<3>(system.offset(b)));
  return fr::point_marker(system.model(b), b, system.body_name(b), local);
}

// `bodies` bodies of random kinds, 0.6 m apart along x and turned at random; body k joined to a random earlier body
// (body 0 to ground) by a joint of a random type at a point between them; then `loops` spherical joints that close
// loops between random pairs of bodies (the test skips a mechanism whose rows then depend on each other); and two springs
// (on rigid-body points or FFRF nodes, whose tangents both Newton matrices hold in full). Gravity.
inline std::unique_ptr<fr::System> random_mechanism(unsigned seed, int bodies, int loops) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto system = std::make_unique<fr::System>();
  for (int k = 0; k < bodies; ++k) {
    const Kind kind = static_cast<Kind>(random() % 3);
    fr::BodyState state;
    state.position = Eigen::Vector3d(0.6 * k, 0.05 * unit(random), 0.05 * unit(random));
    state.orientation = Eigen::AngleAxisd(0.4 * unit(random), Eigen::Vector3d(unit(random), unit(random), 1).normalized())
                            .toRotationMatrix();
    system->add_body(numbered("b", k), model_of(kind), state);
  }
  const Eigen::VectorXd q0 = system->initial_coordinates();
  const fr::JointType types[] = {fr::JointType::spherical, fr::JointType::fixed, fr::JointType::revolute,
                                 fr::JointType::prismatic, fr::JointType::driven_revolute};
  auto q_of = [&](int b) { return b == fr::kGround ? Eigen::VectorXd() : system->body_coordinates(q0, b); };
  for (int k = 0; k < bodies; ++k) {
    const int other = k == 0 ? fr::kGround : static_cast<int>(random() % static_cast<unsigned>(k));
    const Eigen::Vector3d between = q0.segment<3>(system->offset(k)) + Eigen::Vector3d(-0.25, 0.01 * unit(random), 0.0);
    const auto [m1, p] = marker_near(*system, q0, k, between);
    const fr::JointType type = types[random() % 5];
    system->add_joint(fr::make_joint(numbered("j", k), type, m1, point_on(*system, q0, other, p),
                                     Eigen::Vector3d(unit(random), unit(random), 1).normalized(), q_of(k), q_of(other),
                                     [](double t) { return 0.3 * t * t; }));
  }
  for (int l = 0; l < loops; ++l) {
    const int a = static_cast<int>(random() % static_cast<unsigned>(bodies)), b = static_cast<int>(random() % static_cast<unsigned>(bodies));
    if (a == b) continue;
    const auto [m1, p] = marker_near(*system, q0, a, q0.segment<3>(system->offset(a)) + Eigen::Vector3d(0.2, 0.0, 0.01));
    system->add_joint(fr::make_joint(numbered("loop", l), fr::JointType::spherical, m1, point_on(*system, q0, b, p),
                                     Eigen::Vector3d::UnitZ(), q_of(a), q_of(b)));
  }
  for (int s = 0; s < 2; ++s) {
    const int b = static_cast<int>(random() % static_cast<unsigned>(bodies));
    if (!system->model(b).rigid() && !system->model(b).floating()) continue;
    const auto [m1, p] = marker_near(*system, q0, b, q0.segment<3>(system->offset(b)) + Eigen::Vector3d(0.1, 0.02, 0.0));
    system->add_spring({numbered("spring", s), m1, fr::ground_marker(p + Eigen::Vector3d(0.0, 0.3, 0.0)), 200.0, 2.0, 0.25});
  }
  system->set_gravity(Eigen::Vector3d(0, -9.81, 0));
  return system;
}

// A chain of `count` bodies (rigid, GCMS and FFRF in turn, or all of kind `only`) side by side along x, hanging from
// revolute joints about z.
inline std::unique_ptr<fr::System> chain(int count = 16, std::optional<Kind> only = std::nullopt) {
    auto system = std::make_unique<fr::System>();
    for (int k = 0; k < count; ++k) {
      fr::BodyState state;
      state.position = Eigen::Vector3d(0.55 * k, 0.0, 0.0);
      system->add_body(numbered("b", k), model_of(only.value_or(static_cast<Kind>(k % 3))), state);
    }
    const Eigen::VectorXd q0 = system->initial_coordinates();
    for (int k = 0; k < count; ++k) {
      const auto [m1, p] = marker_near(*system, q0, k, Eigen::Vector3d(0.55 * k - 0.25, 0.0, 0.0));
      const int previous = k == 0 ? fr::kGround : k - 1;
      system->add_joint(fr::make_joint(numbered("j", k), fr::JointType::revolute, m1, point_on(*system, q0, previous, p),
                                       Eigen::Vector3d::UnitZ(), system->body_coordinates(q0, k),
                                       previous == fr::kGround ? Eigen::VectorXd() : system->body_coordinates(q0, previous)));
    }
  system->set_gravity(Eigen::Vector3d(0, -9.81, 0));
  return system;
}

}  // namespace mechanisms
