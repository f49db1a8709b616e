#include "flexbody/scene/scene.hpp"
#include "scene_parts.hpp"

#include "flexbody/format/body_file.hpp"
#include "flexbody/format/checkpoint_file.hpp"
#include "flexbody/format/yaml_reader.hpp"
#include "flexbody/runtime/paraview_series.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <numbers>
#include <set>

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
  std::map<std::string, int> bodies;  // name -> index

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
    if (bodies.count(name)) r.fail(it->first, fmt::format("{} is defined twice", where));
    const YAML::Node b = it->second;
    r.expect_map(b, where, {"file", "modes", "formulation", "frame", "position", "rotation", "velocity", "angular_velocity",
                            "damping", "geometric_stiffness"});
    runtime::SceneBody spec;
    const std::string path_text = r.text(r.required(b, "file", where), where + " file");
    spec.file = std::filesystem::path(path_text).is_absolute() ? std::filesystem::path(path_text) : base / path_text;
    spec.stresses = stresses_used.count(name) > 0;
    scene.body_files.push_back(spec.file);
    // modes: all (default) | rigid | a count | full (the unreduced improved ACF of the file's mesh: the reference).
    if (const YAML::Node m = b["modes"]) {
      const std::string text = r.text(m, where + " modes");
      if (text == "rigid") spec.modes = 0;
      else if (text == "full") spec.full = true;
      else if (text != "all") spec.modes = r.count(m, where + " modes");
    }
    // geometric_stiffness: on (true) whenever the body file holds it (fbprep --geometric-stiffness); false turns it off.
    if (const YAML::Node g = b["geometric_stiffness"]) spec.geometric_stiffness = r.truth(g, where + " geometric_stiffness");
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
                              "bodies) or ffrf (the floating frame of reference formulation with the same modes)", where, text));
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
    if (b["angular_velocity"]) placement.angular_velocity = r.vector3(b["angular_velocity"], where + " angular_velocity");
    try {
      bodies[name] = builder.add_body(name, spec, placement);
      scene.body_sha256.push_back(format::recorded_sha256(spec.file));  // right after the reader checked its seal
    } catch (const runtime::SceneError& e) {  // at the key's line (the body's when the key is not written)
      r.fail(b[e.key()] ? b[e.key()] : b, e.what());
    }
  }

  auto body_of = [&](const YAML::Node& node, const std::string& where) -> int {
    const std::string name = r.text(node, where + " body");
    const auto found = bodies.find(name);
    if (found == bodies.end()) r.fail(node, fmt::format("{}: no body '{}' in the scene", where, name));
    return found->second;
  };

  std::vector<YAML::Node> joint_nodes;  // each joint's scene entry, in System::joints() order
  if (const YAML::Node joints = root["joints"]) {
    if (!joints.IsMap()) r.fail(joints, "joints must be a map of names to joints");
    for (auto it = joints.begin(); it != joints.end(); ++it) {
      const std::string name = it->first.Scalar();
      const std::string where = fmt::format("joint '{}'", name);
      const YAML::Node j = it->second;
      r.expect_map(j, where, {"type", "body", "interface", "point", "node", "to", "axis", "speed", "ramp"});
      const runtime::JointType type = joint_type(r, r.required(j, "type", where), where);
      const runtime::Marker m1 = read_marker(r, j, builder, body_of(r.required(j, "body", where), where), where);
      std::optional<runtime::Marker> m2;  // none: to ground, where the first marker is
      if (const YAML::Node to = j["to"]) {
        if (!(to.IsScalar() && to.Scalar() == "ground")) {
          r.expect_map(to, where + " to", {"body", "interface", "point", "node"});
          m2 = read_marker(r, to, builder, body_of(r.required(to, "body", where + " to"), where + " to"), where + " to");
        }
      }
      const bool has_axis = type == runtime::JointType::revolute || type == runtime::JointType::prismatic ||
                            type == runtime::JointType::driven_revolute;
      std::optional<Eigen::Vector3d> axis;
      if (has_axis) axis = r.vector3(r.required(j, "axis", where), where + " axis");
      else if (j["axis"]) r.fail(j["axis"], fmt::format("{}: a {} joint has no axis", where, r.text(j["type"], "type")));
      std::optional<runtime::JointDrive> drive;
      if (type == runtime::JointType::driven_revolute) {
        drive = runtime::JointDrive{r.number(r.required(j, "speed", where), where + " speed"),
                                    j["ramp"] ? r.positive(j["ramp"], where + " ramp") : 0.0};
      } else if (j["speed"] || j["ramp"]) {
        r.fail(j["speed"] ? j["speed"] : j["ramp"], fmt::format("{}: speed and ramp belong to driven-revolute joints", where));
      }
      try {
        builder.add_joint(name, type, m1, m2, axis, drive);
      } catch (const std::invalid_argument& e) {
        r.fail(j, e.what());
      }
      joint_nodes.push_back(j);
    }
  }


  if (const YAML::Node forces = root["forces"]) {
    if (!forces.IsMap()) r.fail(forces, "forces must be a map of names to forces");
    for (auto it = forces.begin(); it != forces.end(); ++it) {
      const std::string where = fmt::format("force '{}'", it->first.Scalar());
      const YAML::Node f = it->second;
      r.expect_map(f, where, {"body", "interface", "point", "node", "force", "torque", "ramp", "frequency"});
      const int body = body_of(r.required(f, "body", where), where);
      if (!f["force"] && !f["torque"]) r.fail(f, fmt::format("{} needs force or torque (or both)", where));
      // Time shape: a linear ramp from 0 over `ramp` seconds, times sin(2π f t) with `frequency` f.
      runtime::LoadShape shape;
      if (f["ramp"]) shape.ramp = r.positive(f["ramp"], where + " ramp");
      if (f["frequency"]) shape.frequency = r.positive(f["frequency"], where + " frequency");
      const runtime::Marker marker = read_marker(r, f, builder, body, where);
      if (const YAML::Node force = f["force"]) builder.add_force(marker, r.vector3(force, where + " force"), shape);
      if (const YAML::Node torque = f["torque"]) builder.add_torque(marker, r.vector3(torque, where + " torque"), shape);
    }
  }

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
        return read_marker(r, e, builder, body_of(r.required(e, "body", end), end), end);
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

  if (const YAML::Node outputs = root["outputs"]) {
    if (!outputs.IsMap()) r.fail(outputs, "outputs must be a map of names to outputs");
    for (auto it = outputs.begin(); it != outputs.end(); ++it) {
      Sensor s;
      s.name = it->first.Scalar();
      const std::string where = fmt::format("output '{}'", s.name);
      if (s.name.empty() || s.name.find_first_of("/\\") != std::string::npos || s.name == "monitors")
        r.fail(it->first, fmt::format("{}: the name must be a plain file name (not 'monitors')", where));
      const YAML::Node o = it->second;
      r.expect_map(o, where, {"body", "interface", "point", "node", "region", "joint", "quantities"});
      const YAML::Node quantities = r.required(o, "quantities", where);
      if (!quantities.IsSequence() || quantities.size() == 0) r.fail(quantities, fmt::format("{} quantities must be a list", where));
      std::vector<std::string> allowed;
      if (o["joint"]) {
        s.kind = Sensor::Kind::joint;
        const std::string joint = r.text(o["joint"], where + " joint");
        const auto& joints = scene.system.joints();
        std::size_t k = 0;
        while (k < joints.size() && joints[k].name != joint) ++k;
        if (k == joints.size()) r.fail(o["joint"], fmt::format("{}: no joint '{}' in the scene", where, joint));
        s.joint = k;
        allowed = {"reaction_force", "reaction_moment"};
      } else {
        const int body = body_of(r.required(o, "body", where), where);
        s.body = body;
        if (const YAML::Node region = o["region"]) {
          s.kind = Sensor::Kind::region;
          const std::string name = r.text(region, where + " region");
          const auto& regions = scene.system.model(body).recovery;
          std::string known;
          for (const auto& g : regions) known += (known.empty() ? "" : ", ") + g.name;
          while (s.region < regions.size() && regions[s.region].name != name) ++s.region;
          if (scene.system.model(body).sparse)
            r.fail(region, fmt::format("{}: body '{}' is modes: full, which has no output regions (their stresses are "
                                       "recovered from the body file's modes); follow its nodes with node markers",
                                       where, scene.system.body_name(body)));
          if (s.region == regions.size())
            r.fail(region, fmt::format("{}: the body file has no output region '{}' (regions: {})", where, name,
                                       known.empty() ? "none; name output_regions in its body spec" : known));
          allowed = {"displacement", "stress"};
        } else if (o["interface"] || o["point"] || o["node"]) {
          s.kind = Sensor::Kind::marker;
          s.marker = read_marker(r, o, builder, body, where);
          allowed = {"position", "velocity", "orientation"};
        } else {
          s.kind = Sensor::Kind::modal;
          allowed = {"modal_coordinates"};
          if (scene.system.model(body).sparse)
            r.fail(o, fmt::format("{}: body '{}' is modes: full, which has no modal coordinates; follow its nodes with "
                                  "node markers", where, scene.system.body_name(body)));
        }
      }
      for (std::size_t k = 0; k < quantities.size(); ++k) {
        const std::string q = r.text(quantities[k], where + " quantity");
        if (std::find(allowed.begin(), allowed.end(), q) == allowed.end())
          r.fail(quantities[k], fmt::format("{}: quantity '{}' is not available here; use {}", where, q, fmt::join(allowed, ", ")));
        s.quantities.push_back(q);
      }
      scene.sensors.push_back(std::move(s));
    }
  }

  // paraview: {bodies: [names] (default: all), every: n steps (default: about 100 frames), stresses: true}
  if (const YAML::Node paraview = root["paraview"]) {
    r.expect_map(paraview, "paraview", {"bodies", "every", "interval", "stresses"});
    scene.paraview_at = paraview["every"]      ? r.at(paraview["every"])
                        : paraview["interval"] ? r.at(paraview["interval"])
                                               : key_at(r, root, "paraview");
    bool stresses = true;
    if (const YAML::Node s = paraview["stresses"]) stresses = r.truth(s, "paraview stresses");
    std::vector<std::pair<int, YAML::Node>> chosen;
    if (const YAML::Node list = paraview["bodies"]) {
      if (!list.IsSequence() || list.size() == 0) r.fail(list, "paraview bodies must be a list of body names");
      for (std::size_t k = 0; k < list.size(); ++k) chosen.emplace_back(body_of(list[k], "paraview"), list[k]);
    } else {
      for (int b = 0; b < scene.system.body_count(); ++b) chosen.emplace_back(b, paraview);
    }
    for (const auto& [body, node] : chosen) {
      if (std::any_of(scene.paraview.begin(), scene.paraview.end(), [b = body](const SurfaceSeries& s) { return s.body == b; }))
        r.fail(node, fmt::format("paraview: body '{}' is named twice", scene.system.body_name(body)));
      // A full-order body has no stress modes: by default its series shows displacements only.
      const bool full = scene.system.model(body).sparse != nullptr;
      if (full && stresses && paraview["stresses"])
        r.fail(paraview["stresses"], fmt::format("paraview: body '{}' is modes: full, whose stresses fbsim does not recover "
                                                 "(they come from the body file's modes); set stresses: false",
                                                 scene.system.body_name(body)));
      const bool body_stresses = stresses && !full;
      try {  // the checks of the series itself (surface stresses recovered?), before anything runs
        const runtime::ParaViewSeries check({}, scene.system.body_name(body), scene.system.model(body), body_stresses);
      } catch (const std::invalid_argument& e) {
        r.fail(node, fmt::format("paraview: body '{}': {}", scene.system.body_name(body), e.what()));
      }
      scene.paraview.push_back({body, body_stresses});
    }
    const bool automatic = scene.integrator.error_tolerance > 0.0;  // step: auto: frames by time
    const long steps = automatic ? 1 : static_cast<long>(step_count(scene.end_time, scene.integrator.step));
    scene.paraview_every = static_cast<int>(std::max(1L, (steps + 99) / 100));
    if (automatic && !paraview["interval"]) scene.paraview_interval = scene.end_time / kAutoFrames;
    if (const YAML::Node every = paraview["every"]) {
      if (automatic) r.fail(every, "paraview every counts steps, which step: auto chooses; give interval (seconds)");
      scene.paraview_every = r.count(every, "paraview every");
      if (scene.paraview_every < 1) r.fail(every, "paraview every must be at least 1");
    }
    if (const YAML::Node interval = paraview["interval"]) {  // [s]: frames at the same times whatever the step
      if (paraview["every"]) r.fail(interval, "paraview: every (steps) and interval (seconds) are both given; give one");
      scene.paraview_interval = r.positive(interval, "paraview interval");
    }
  }
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
    r.fail(e.joint < joint_nodes.size() ? joint_nodes[e.joint] : root, e.what());
  } catch (const std::invalid_argument& e) {
    r.fail(root["bodies"], e.what());  // a degenerate body file
  }
  return scene;
}

}  // namespace flexbody::scene
