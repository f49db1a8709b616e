#pragma once
// A scene file read key by key: what the readers of its keys share (a marker read from its map, a joint's type, the
// scene being read) and the readers themselves, in the order read_scene (scene_file.cpp) calls them. flexbody::scene's
// own, not installed.

#include "flexbody/format/yaml_reader.hpp"
#include "flexbody/runtime/joint.hpp"
#include "flexbody/runtime/marker.hpp"
#include "flexbody/runtime/scene_builder.hpp"
#include "flexbody/scene/scene.hpp"

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace flexbody::scene {

using Reader = format::YamlReader;

/// A marker on body `body` (its index) from exactly one of interface (name), point (input-frame coordinates [m]),
/// node (index), made by the scene's builder.
[[nodiscard]] runtime::Marker read_marker(const Reader& r, const YAML::Node& map, const runtime::SceneBuilder& builder,
                                          int body, const std::string& where);

/// "<file>:<line>" of key `key` of `map` (the key's own line: a block map's value starts on the next).
[[nodiscard]] std::string key_at(const Reader& r, const YAML::Node& map, const char* key);

/// spherical, fixed, revolute, prismatic or driven-revolute; anything else fails on its line.
[[nodiscard]] runtime::JointType joint_type(const Reader& r, const YAML::Node& node, const std::string& where);

/// How often a run records (rows, frames): `every_key` counts steps (at least 1; refused under step: auto, whose steps
/// the controller chooses) into `every`, `interval_key` gives seconds into `interval`; not both. `what` names the map
/// in messages ("integrator", "paraview"). Each is left as it is when its key is absent.
void read_cadence(const Reader& r, const YAML::Node& map, const std::string& what, const char* every_key,
                  const char* interval_key, bool automatic, int& every, std::optional<double>& interval);

/// A scene being read: its document, the scene and its builder, and what the keys read so far defined.
struct SceneReading {
  const Reader& r;
  const YAML::Node& root;
  Scene& scene;
  runtime::SceneBuilder& builder;
  std::map<std::string, int> bodies;    ///< name -> index (read_bodies)
  std::vector<YAML::Node> joint_nodes;  ///< each joint's entry, in System::joints() order (read_joints)
  /// The index of the body `node` names; fails on its line when the scene has no body of that name.
  [[nodiscard]] int body_of(const YAML::Node& node, const std::string& where) const;
};

/// `bodies` (required): each body's file (relative to `base`), modes, formulation, damping and placement, added to
/// the builder; a body's stress modes are kept only where an output or a ParaView series uses them (scene_bodies.cpp).
void read_bodies(SceneReading& reading, const std::filesystem::path& base);
void read_joints(SceneReading& reading);  ///< `joints` (scene_joints.cpp)
void read_forces(
    SceneReading& reading);  ///< `forces`: point forces and torques with their time shape (scene_loads.cpp)
void read_springs(SceneReading& reading);  ///< `springs` (scene_loads.cpp)
/// The `integrator` map (required) into scene.integrator, scene.end_time (or overrides.end_time) and
/// scene.output_every, each value checked against the line it is on (scene_integrator.cpp).
void read_integrator(const Reader& r, const YAML::Node& root, const SceneOverrides& overrides, Scene& scene);
void read_outputs(SceneReading& reading);   ///< `outputs`: the CSV files' sensors (scene_outputs.cpp)
void read_paraview(SceneReading& reading);  ///< `paraview`: the series, after the integrator (scene_outputs.cpp)

}  // namespace flexbody::scene
