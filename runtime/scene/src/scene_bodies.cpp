// A scene's `bodies` map: each body's file, modes, formulation, damping and placement (scene_parts.hpp: read_bodies).

#include "scene_parts.hpp"

#include "flexbody/format/body_file.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <numbers>
#include <set>

namespace flexbody::scene {

void read_bodies(SceneReading& reading, const std::filesystem::path& base) {
  const Reader& r = reading.r;
  const YAML::Node& root = reading.root;
  Scene& scene = reading.scene;
  runtime::SceneBuilder& builder = reading.builder;
  const YAML::Node body_map = r.required(root, "bodies", "the scene");
  if (!body_map.IsMap() || body_map.size() == 0) r.fail(body_map, "bodies must be a map of names to bodies");
  // A scene keeps only what its outputs use: a body's stress modes (most of a body file: 6.8 of the bracket's 7.9 MB)
  // only where an output names one of its regions or a ParaView series shows its stresses, so that a chain of a
  // thousand copies of a part does not hold a thousand copies of them.
  std::set<std::string> stresses_used;
  if (const YAML::Node outputs = root["outputs"]; outputs && outputs.IsMap())
    for (auto it = outputs.begin(); it != outputs.end(); ++it)
      if (it->second.IsMap() && it->second["region"] && it->second["body"] && it->second["body"].IsScalar())
        stresses_used.insert(it->second["body"].Scalar());
  if (const YAML::Node paraview = root["paraview"]; paraview && paraview.IsMap()) {
    const YAML::Node stresses = paraview["stresses"];
    if (!(stresses && stresses.IsScalar() && stresses.Scalar() == "false")) {
      const YAML::Node list = paraview["bodies"];
      if (list && list.IsSequence()) {
        for (const YAML::Node& name : list)
          if (name.IsScalar()) stresses_used.insert(name.Scalar());
      } else {
        for (auto it = body_map.begin(); it != body_map.end(); ++it) stresses_used.insert(it->first.Scalar());
      }
    }
  }
  for (auto it = body_map.begin(); it != body_map.end(); ++it) {
    const std::string name = it->first.Scalar();
    const std::string where = fmt::format("body '{}'", name);
    if (reading.bodies.count(name)) r.fail(it->first, fmt::format("{} is defined twice", where));
    const YAML::Node b = it->second;
    r.expect_map(b, where,
                 {"file", "modes", "formulation", "frame", "position", "rotation", "velocity", "angular_velocity",
                  "damping", "geometric_stiffness"});
    runtime::SceneBody spec;
    const std::string path_text = r.text(r.required(b, "file", where), where + " file");
    spec.file = std::filesystem::path(path_text).is_absolute() ? std::filesystem::path(path_text) : base / path_text;
    spec.stresses = stresses_used.count(name) > 0;
    scene.body_files.push_back(spec.file);
    // modes: all (default) | rigid | a count | full (the unreduced improved ACF of the file's mesh: the reference).
    if (const YAML::Node m = b["modes"]) {
      const std::string text = r.text(m, where + " modes");
      if (text == "rigid")
        spec.modes = 0;
      else if (text == "full")
        spec.full = true;
      else if (text != "all")
        spec.modes = r.count(m, where + " modes");
    }
    // geometric_stiffness: on (true) whenever the body file holds it (fbprep --geometric-stiffness); false turns it
    // off.
    if (const YAML::Node g = b["geometric_stiffness"])
      spec.geometric_stiffness = r.truth(g, where + " geometric_stiffness");
    // damping: modal: ζ (all modes) or [ζ_1, ...]; rayleigh: {alpha, beta}
    if (const YAML::Node damping = b["damping"]) {
      r.expect_map(damping, where + " damping", {"modal", "rayleigh"});
      runtime::BodyDamping& d = spec.damping.emplace();
      if (const YAML::Node modal = damping["modal"]) {
        if (modal.IsSequence()) {
          d.modal_ratios = Eigen::VectorXd(static_cast<Eigen::Index>(modal.size()));
          for (std::size_t k = 0; k < modal.size(); ++k)
            (*d.modal_ratios)(static_cast<Eigen::Index>(k)) = r.number(modal[k], where + " damping modal");
        } else {
          d.modal = r.number(modal, where + " damping modal");
        }
      }
      if (const YAML::Node rayleigh = damping["rayleigh"]) {
        r.expect_map(rayleigh, where + " damping rayleigh", {"alpha", "beta"});
        if (rayleigh["alpha"]) d.alpha = r.number(rayleigh["alpha"], where + " damping alpha");
        if (rayleigh["beta"]) d.beta = r.number(rayleigh["beta"], where + " damping beta");
      }
    }
    // formulation: gcms (default for elastic bodies) | ffrf; frame (formulation: ffrf only): mean-axis (default) |
    // {interface: NAME}. A rigid body (modes: rigid) moves in the floating frame's 7 coordinates, position and Euler
    // parameters, with one normalisation row, unless the scene asks for the GCMS's 12 (τ and A) with 6 orthogonality
    // rows: the same motion with 18 unknowns per body instead of 8 (a 1024-link chain 30 % faster per step,
    // bench/README.md).
    if (const YAML::Node f = b["formulation"]) {
      const std::string text = r.text(f, where + " formulation");
      if (text != "gcms" && text != "ffrf")
        r.fail(f, fmt::format("{} formulation '{}' is unknown; use gcms (the improved GCMS, the default for elastic "
                              "bodies) or ffrf (the floating frame of reference formulation with the same modes)",
                              where, text));
      spec.formulation = text == "ffrf" ? runtime::SceneBody::Formulation::ffrf : runtime::SceneBody::Formulation::gcms;
    }
    if (const YAML::Node frame = b["frame"]) {
      if (frame.IsMap()) {
        r.expect_map(frame, where + " frame", {"interface"});
        spec.frame = runtime::FloatingFrame::interface;
        spec.frame_interface = r.text(r.required(frame, "interface", where + " frame"), where + " frame interface");
      } else if (const std::string text = r.text(frame, where + " frame"); text == "mean-axis") {
        spec.frame = runtime::FloatingFrame::mean_axis;
      } else if (spec.formulation == runtime::SceneBody::Formulation::ffrf) {
        r.fail(frame, fmt::format("{} frame '{}' is unknown; use mean-axis or {{interface: NAME}}", where, text));
      } else {
        spec.frame = runtime::FloatingFrame::mean_axis;  // refused below: a frame belongs to formulation ffrf
      }
    }
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    if (const YAML::Node rot = b["rotation"]) {
      r.expect_map(rot, where + " rotation", {"axis", "angle_deg"});
      const Eigen::Vector3d axis = r.vector3(r.required(rot, "axis", where + " rotation"), where + " rotation axis");
      if (!(axis.norm() > 0)) r.fail(rot["axis"], fmt::format("{} rotation axis must be non-zero", where));
      const double angle = r.number(r.required(rot, "angle_deg", where + " rotation"), where + " rotation angle_deg");
      rotation = Eigen::AngleAxisd(angle * std::numbers::pi / 180.0, axis.normalized()).toRotationMatrix();
    }
    runtime::Placement placement;  // the input frame's origin goes to `position`
    placement.rotation = rotation;
    if (b["position"]) placement.position = r.vector3(b["position"], where + " position");
    if (b["velocity"]) placement.velocity = r.vector3(b["velocity"], where + " velocity");
    if (b["angular_velocity"])
      placement.angular_velocity = r.vector3(b["angular_velocity"], where + " angular_velocity");
    try {
      reading.bodies[name] = builder.add_body(name, spec, placement);
      scene.body_sha256.push_back(format::recorded_sha256(spec.file));  // right after the reader checked its seal
    } catch (const runtime::SceneError& e) {  // at the key's line (the body's when the key is not written)
      r.fail(b[e.key()] ? b[e.key()] : b, e.what());
    }
  }
}

}  // namespace flexbody::scene
