// A scene file: read_scene reads its keys in order (the readers in scene_parts.hpp) and finishes the scene.
#include "flexbody/scene/scene.hpp"
#include "scene_parts.hpp"

#include "flexbody/format/checkpoint_file.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <iterator>

namespace flexbody::scene {

Scene read_scene(const std::filesystem::path& file, const SceneOverrides& overrides) {
  Scene scene = read_scene(Reader(file.string()).load("scene"), file.string(), file.parent_path(), overrides);
  // The bytes, not the document: a checkpoint belongs to this file as it is (a changed comment changes it too).
  std::ifstream in(file, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  scene.source_sha256 = format::sha256_hex(bytes);
  return scene;
}

Scene read_scene(const YAML::Node& root, const std::string& source, const std::filesystem::path& base,
                 const SceneOverrides& overrides, const SceneExtras& extras) {
  const Reader r(source);
  r.expect_map(root, "the scene",
               {"bodies", "joints", "forces", "springs", "gravity", "integrator", "outputs", "monitors", "paraview",
                "assembly", "output_budget", "checkpoint"});
  Scene scene;
  scene.source_sha256 = format::sha256_hex(YAML::Dump(root));
  runtime::SceneBuilder builder(scene.system);

  SceneReading reading{r, root, scene, builder, {}, {}};
  read_bodies(reading, base);
  read_joints(reading);
  read_forces(reading);
  read_springs(reading);
  if (extras) extras(builder);

  if (const YAML::Node g = root["gravity"]) scene.system.set_gravity(r.vector3(g, "gravity"));

  read_integrator(r, root, overrides, scene);
  if (scene.integrator.error_tolerance > 0.0)  // refused at its line here; the integrator refuses it too, without one
    for (int b = 0; b < scene.system.body_count(); ++b)
      if (scene.system.model(b).sparse)
        r.fail(root["bodies"][scene.system.body_name(b)]["modes"],
               fmt::format("body '{}' is modes: full, which step: auto cannot measure (its error estimate counts the "
                           "vibrations a step resolves, and the full-order model has no modal split); give the scene a "
                           "fixed step", scene.system.body_name(b)));
  if (const YAML::Node monitors = root["monitors"]) scene.monitors = r.truth(monitors, "monitors");

  read_outputs(reading);
  read_paraview(reading);
  // output_budget: {size: SIZE, files: N}: what a run may write into its directory (output_budget.hpp); --max-output
  // overrides the size.
  if (const YAML::Node budget = root["output_budget"]) {
    r.expect_map(budget, "output_budget", {"size", "files"});
    if (const YAML::Node size = budget["size"]) {
      try {
        scene.budget.bytes = parse_size(r.text(size, "output_budget size"));
      } catch (const std::invalid_argument& e) {
        r.fail(size, fmt::format("output_budget size: {}", e.what()));
      }
    }
    if (const YAML::Node files = budget["files"]) {
      scene.budget.files = r.number(files, "output_budget files");
      if (!(scene.budget.files >= 1.0) || scene.budget.files != std::floor(scene.budget.files))
        r.fail(files, fmt::format("output_budget files must be a whole number of at least 1, got {}", scene.budget.files));
    }
  }
  if (overrides.max_output) scene.budget.bytes = *overrides.max_output;
  // checkpoint: {interval: SECONDS}: DIR/checkpoint.h5 every so many seconds of wall-clock time (docs/scenes.md).
  if (const YAML::Node checkpoint = root["checkpoint"]) {
    r.expect_map(checkpoint, "checkpoint", {"interval"});
    scene.checkpoint_interval = r.positive(r.required(checkpoint, "interval", "checkpoint"), "checkpoint interval");
  }

  // assembly: {tolerance: fraction of a body's size}: close the joints' gaps (an interface's point comes from a mesh,
  // micrometres off the CAD's nominal position) by the least mass-weighted move of the bodies
  // (runtime/initial_assembly.hpp).
  runtime::InitialAssemblyOptions assembly;
  const YAML::Node assembly_node = root["assembly"];
  if (assembly_node) {
    r.expect_map(assembly_node, "assembly", {"tolerance"});
    if (const YAML::Node tol = assembly_node["tolerance"]) {
      assembly.tolerance = r.positive(tol, "assembly tolerance");
      if (assembly.tolerance > 1.0)
        r.fail(tol, fmt::format("assembly tolerance {} is a fraction of a body's size; at most 1", assembly.tolerance));
    }
  }
  try {
    finish_scene(scene, assembly);
  } catch (const runtime::InitialAssemblyError& e) {
    r.fail(e.joint < reading.joint_nodes.size() ? reading.joint_nodes[e.joint] : root, e.what());
  } catch (const std::invalid_argument& e) {
    r.fail(root["bodies"], e.what());  // a degenerate body file
  }
  return scene;
}

}  // namespace flexbody::scene
