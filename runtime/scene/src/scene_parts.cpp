#include "scene_parts.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace flexbody::scene {

void read_cadence(const Reader& r, const YAML::Node& map, const std::string& what, const char* every_key,
                  const char* interval_key, bool automatic, int& every, std::optional<double>& interval) {
  if (const YAML::Node node = map[every_key]) {
    if (automatic)
      r.fail(node, fmt::format("{} {} counts steps, which step: auto chooses; give {} (seconds)", what, every_key,
                               interval_key));
    every = r.count(node, fmt::format("{} {}", what, every_key));
    if (every < 1) r.fail(node, fmt::format("{} {} must be at least 1", what, every_key));
  }
  if (const YAML::Node node = map[interval_key]) {  // [s]: at the same times whatever the step
    if (map[every_key])
      r.fail(node,
             fmt::format("{}: {} (steps) and {} (seconds) are both given; give one", what, every_key, interval_key));
    interval = r.positive(node, fmt::format("{} {}", what, interval_key));
  }
}

int SceneReading::body_of(const YAML::Node& node, const std::string& where) const {
  const std::string name = r.text(node, where + " body");
  const auto found = bodies.find(name);
  if (found == bodies.end()) r.fail(node, fmt::format("{}: no body '{}' in the scene", where, name));
  return found->second;
}

// A marker on `body` from exactly one of interface (name), point (input-frame coordinates [m]), node (index).
runtime::Marker read_marker(const Reader& r, const YAML::Node& map, const runtime::SceneBuilder& builder, int body,
                            const std::string& where) {
  const std::string& name = builder.system().body_name(body);
  int given = 0;
  for (const char* key : {"interface", "point", "node"}) given += map[key].IsDefined() ? 1 : 0;
  if (given != 1) r.fail(map, fmt::format("{} needs exactly one of interface, point, node", where));
  if (const YAML::Node p = map["point"]) return builder.point(name, r.vector3(p, where + " point"));
  const YAML::Node key = map["interface"] ? map["interface"] : map["node"];
  const std::string interface = map["interface"] ? r.text(key, where + " interface") : std::string();
  const int node = map["node"] ? r.count(key, where + " node") : 0;
  try {
    return map["interface"] ? builder.interface(name, interface) : builder.node(name, node);
  } catch (const std::invalid_argument& e) {  // an unknown interface or node, named with the body file's ones
    r.fail(key, fmt::format("{}: {}", where, e.what()));
  }
}

std::string key_at(const Reader& r, const YAML::Node& map, const char* key) {
  for (auto it = map.begin(); it != map.end(); ++it)
    if (it->first.IsScalar() && it->first.Scalar() == key) return r.at(it->first);
  return r.at(map);
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

}  // namespace flexbody::scene
