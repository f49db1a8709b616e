// A scene's `joints` map (scene_parts.hpp: read_joints).

#include "scene_parts.hpp"

#include <fmt/format.h>

#include <optional>

namespace flexbody::scene {

void read_joints(SceneReading& reading) {
  const Reader& r = reading.r;
  const YAML::Node& root = reading.root;
  runtime::SceneBuilder& builder = reading.builder;
  if (const YAML::Node joints = root["joints"]) {
    if (!joints.IsMap()) r.fail(joints, "joints must be a map of names to joints");
    for (auto it = joints.begin(); it != joints.end(); ++it) {
      const std::string name = it->first.Scalar();
      const std::string where = fmt::format("joint '{}'", name);
      const YAML::Node j = it->second;
      r.expect_map(j, where, {"type", "body", "interface", "point", "node", "to", "axis", "speed", "ramp"});
      const runtime::JointType type = joint_type(r, r.required(j, "type", where), where);
      const runtime::Marker m1 =
          read_marker(r, j, builder, reading.body_of(r.required(j, "body", where), where), where);
      std::optional<runtime::Marker> m2;  // none: to ground, where the first marker is
      if (const YAML::Node to = j["to"]) {
        if (!(to.IsScalar() && to.Scalar() == "ground")) {
          r.expect_map(to, where + " to", {"body", "interface", "point", "node"});
          m2 = read_marker(r, to, builder, reading.body_of(r.required(to, "body", where + " to"), where + " to"),
                           where + " to");
        }
      }
      const bool has_axis = type == runtime::JointType::revolute || type == runtime::JointType::prismatic ||
                            type == runtime::JointType::driven_revolute;
      std::optional<Eigen::Vector3d> axis;
      if (has_axis)
        axis = r.vector3(r.required(j, "axis", where), where + " axis");
      else if (j["axis"])
        r.fail(j["axis"], fmt::format("{}: a {} joint has no axis", where, r.text(j["type"], "type")));
      std::optional<runtime::JointDrive> drive;
      if (type == runtime::JointType::driven_revolute) {
        drive = runtime::JointDrive{r.number(r.required(j, "speed", where), where + " speed"),
                                    j["ramp"] ? r.positive(j["ramp"], where + " ramp") : 0.0};
      } else if (j["speed"] || j["ramp"]) {
        r.fail(j["speed"] ? j["speed"] : j["ramp"],
               fmt::format("{}: speed and ramp belong to driven-revolute joints", where));
      }
      try {
        builder.add_joint(name, type, m1, m2, axis, drive);
      } catch (const std::invalid_argument& e) {
        r.fail(j, e.what());
      }
      reading.joint_nodes.push_back(j);
    }
  }
}

}  // namespace flexbody::scene
