#pragma once
// The pieces of a scene that several of its keys share: a marker read from its map and a joint's type (scene_file.cpp;
// flexbody::scene's own, not installed).

#include "flexbody/format/yaml_reader.hpp"
#include "flexbody/runtime/joint.hpp"
#include "flexbody/runtime/marker.hpp"
#include "flexbody/runtime/scene_builder.hpp"

#include <string>

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

}  // namespace flexbody::scene
