// A scene's `forces` and `springs` maps (scene_parts.hpp: read_forces, read_springs).

#include "scene_parts.hpp"

#include <fmt/format.h>

#include <optional>

namespace flexbody::scene {

void read_forces(SceneReading& reading) {
  const Reader& r = reading.r;
  const YAML::Node& root = reading.root;
  runtime::SceneBuilder& builder = reading.builder;
  if (const YAML::Node forces = root["forces"]) {
    if (!forces.IsMap()) r.fail(forces, "forces must be a map of names to forces");
    for (auto it = forces.begin(); it != forces.end(); ++it) {
      const std::string where = fmt::format("force '{}'", it->first.Scalar());
      const YAML::Node f = it->second;
      r.expect_map(f, where, {"body", "interface", "point", "node", "force", "torque", "ramp", "frequency"});
      const int body = reading.body_of(r.required(f, "body", where), where);
      if (!f["force"] && !f["torque"]) r.fail(f, fmt::format("{} needs force or torque (or both)", where));
      // Time shape: a linear ramp from 0 over `ramp` seconds, times sin(2π f t) with `frequency` f.
      runtime::LoadShape shape;
      if (f["ramp"]) shape.ramp = r.positive(f["ramp"], where + " ramp");
      if (f["frequency"]) shape.frequency = r.positive(f["frequency"], where + " frequency");
      const runtime::Marker marker = read_marker(r, f, builder, body, where);
      if (const YAML::Node force = f["force"]) builder.add_force(marker, r.vector3(force, where + " force"), shape);
      if (const YAML::Node torque = f["torque"])
        builder.add_torque(marker, r.vector3(torque, where + " torque"), shape);
    }
  }
}

void read_springs(SceneReading& reading) {
  const Reader& r = reading.r;
  const YAML::Node& root = reading.root;
  runtime::SceneBuilder& builder = reading.builder;
  if (const YAML::Node springs = root["springs"]) {
    if (!springs.IsMap()) r.fail(springs, "springs must be a map of names to spring-dampers");
    for (auto it = springs.begin(); it != springs.end(); ++it) {
      const std::string where = fmt::format("spring '{}'", it->first.Scalar());
      const YAML::Node sp = it->second;
      r.expect_map(sp, where, {"from", "to", "stiffness", "damping", "length"});
      auto endpoint = [&](const char* key) {
        const YAML::Node e = r.required(sp, key, where);
        const std::string end = fmt::format("{} {}", where, key);
        if (e.IsMap() && e["ground"]) {
          r.expect_map(e, end, {"ground"});
          return runtime::ground_marker(r.vector3(e["ground"], end + " ground"));
        }
        r.expect_map(e, end, {"body", "interface", "point", "node"});
        return read_marker(r, e, builder, reading.body_of(r.required(e, "body", end), end), end);
      };
      const runtime::Marker from = endpoint("from"), to = endpoint("to");
      const double stiffness = r.number(r.required(sp, "stiffness", where), where + " stiffness");
      const double damping = sp["damping"] ? r.number(sp["damping"], where + " damping") : 0.0;
      std::optional<double> length;  // default: the initial distance (no preload)
      if (sp["length"]) length = r.number(sp["length"], where + " length");
      try {
        builder.add_spring(it->first.Scalar(), from, to, stiffness, damping, length);
      } catch (const std::invalid_argument& e) {
        r.fail(sp, e.what());
      }
    }
  }
}

}  // namespace flexbody::scene
