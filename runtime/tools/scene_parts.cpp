#include "scene_parts.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace flexbody::fbsim {

// A marker on `body` from exactly one of interface (name), point (input-frame coordinates [m]), node (index).
runtime::Marker read_marker(const Reader& r, const YAML::Node& map, const runtime::System& system, int body,
                            const LoadedBody& loaded, const std::string& where) {
  const runtime::BodyModel& model = system.model(body);
  const std::string& name = system.body_name(body);
  int given = 0;
  for (const char* key : {"interface", "point", "node"}) given += map[key].IsDefined() ? 1 : 0;
  if (given != 1) r.fail(map, fmt::format("{} needs exactly one of interface, point, node", where));
  if (const YAML::Node p = map["point"])
    return runtime::point_marker(model, body, name, r.vector3(p, where + " point") - loaded.com_input);
  const YAML::Node key = map["interface"] ? map["interface"] : map["node"];
  const std::string interface = map["interface"] ? r.text(key, where + " interface") : std::string();
  const int node = map["node"] ? r.count(key, where + " node") : 0;
  try {
    return map["interface"] ? runtime::interface_marker(model, body, name, interface)
                            : runtime::node_marker(model, body, name, node);
  } catch (const std::invalid_argument& e) {  // an unknown interface or node, named with the body file's ones
    r.fail(key, fmt::format("{}: {}", where, e.what()));
  }
}

runtime::JointType joint_type(const Reader& r, const YAML::Node& node, const std::string& where) {
  const std::string t = r.text(node, where + " type");
  if (t == "spherical") return runtime::JointType::spherical;
  if (t == "fixed") return runtime::JointType::fixed;
  if (t == "revolute") return runtime::JointType::revolute;
  if (t == "prismatic") return runtime::JointType::prismatic;
  if (t == "driven-revolute") return runtime::JointType::driven_revolute;
  r.fail(node, fmt::format("{}: type '{}' is unknown; use spherical, fixed, revolute, prismatic or driven-revolute", where, t));
}

// φ(t) of a driven revolute joint: speed Ω [rad/s] reached smoothly over `ramp` seconds (φ̇ = Ω (1 − cos πt/T) / 2).
std::function<double(double)> ramped_angle(double speed, double ramp) {
  return [speed, ramp](double t) {
    if (ramp <= 0.0 || t >= ramp) return speed * (t - 0.5 * ramp);
    return 0.5 * speed * (t - ramp / std::numbers::pi * std::sin(std::numbers::pi * t / ramp));
  };
}

// Its φ̇ [rad/s], so that the constraints' time derivative is exact (joint.hpp: Joint::angle_rate).
std::function<double(double)> ramped_angle_rate(double speed, double ramp) {
  return [speed, ramp](double t) {
    if (ramp <= 0.0 || t >= ramp) return speed;
    return 0.5 * speed * (1.0 - std::cos(std::numbers::pi * t / ramp));
  };
}

}  // namespace flexbody::fbsim
