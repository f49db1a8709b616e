#pragma once
// The pieces of a scene that several of its keys share: a body as the scene loaded it, a marker read from its map,
// a joint's type, and a driven joint's angle (scene.cpp; fbsim's own, not installed).

#include "flexbody/format/yaml_reader.hpp"
#include "flexbody/runtime/joint.hpp"
#include "flexbody/runtime/marker.hpp"
#include "flexbody/runtime/system.hpp"

#include <Eigen/Core>

#include <functional>
#include <string>

namespace flexbody::fbsim {

using Reader = format::YamlReader;

struct LoadedBody {
  int index = 0;
  Eigen::Vector3d com_input = Eigen::Vector3d::Zero();  ///< the body file's centre of mass, input frame
};

/// A marker on `body` from exactly one of interface (name), point (input-frame coordinates [m]), node (index).
[[nodiscard]] runtime::Marker read_marker(const Reader& r, const YAML::Node& map, const runtime::System& system,
                                          int body, const LoadedBody& loaded, const std::string& where);

/// spherical, fixed, revolute, prismatic or driven-revolute; anything else fails on its line.
[[nodiscard]] runtime::JointType joint_type(const Reader& r, const YAML::Node& node, const std::string& where);

/// φ(t) of a driven revolute joint: speed Ω [rad/s] reached smoothly over `ramp` seconds (φ̇ = Ω (1 − cos πt/T) / 2).
[[nodiscard]] std::function<double(double)> ramped_angle(double speed, double ramp);
/// Its φ̇ [rad/s], so that the constraints' time derivative is exact (joint.hpp: Joint::angle_rate).
[[nodiscard]] std::function<double(double)> ramped_angle_rate(double speed, double ramp);

}  // namespace flexbody::fbsim
