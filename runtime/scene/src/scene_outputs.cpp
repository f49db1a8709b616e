// A scene's `outputs` and `paraview` maps: what a run records (scene_parts.hpp: read_outputs, read_paraview).

#include "scene_parts.hpp"

#include "flexbody/runtime/paraview_series.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

namespace flexbody::scene {

void read_outputs(SceneReading& reading) {
  const Reader& r = reading.r;
  const YAML::Node& root = reading.root;
  Scene& scene = reading.scene;
  runtime::SceneBuilder& builder = reading.builder;
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
      if (!quantities.IsSequence() || quantities.size() == 0)
        r.fail(quantities, fmt::format("{} quantities must be a list", where));
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
        const int body = reading.body_of(r.required(o, "body", where), where);
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
                                  "node markers",
                                  where, scene.system.body_name(body)));
        }
      }
      for (std::size_t k = 0; k < quantities.size(); ++k) {
        const std::string q = r.text(quantities[k], where + " quantity");
        if (std::find(allowed.begin(), allowed.end(), q) == allowed.end())
          r.fail(quantities[k],
                 fmt::format("{}: quantity '{}' is not available here; use {}", where, q, fmt::join(allowed, ", ")));
        s.quantities.push_back(q);
      }
      scene.sensors.push_back(std::move(s));
    }
  }
}

void read_paraview(SceneReading& reading) {
  const Reader& r = reading.r;
  const YAML::Node& root = reading.root;
  Scene& scene = reading.scene;
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
      for (std::size_t k = 0; k < list.size(); ++k) chosen.emplace_back(reading.body_of(list[k], "paraview"), list[k]);
    } else {
      for (int b = 0; b < scene.system.body_count(); ++b) chosen.emplace_back(b, paraview);
    }
    for (const auto& [body, node] : chosen) {
      if (std::any_of(scene.paraview.begin(), scene.paraview.end(),
                      [b = body](const SurfaceSeries& s) { return s.body == b; }))
        r.fail(node, fmt::format("paraview: body '{}' is named twice", scene.system.body_name(body)));
      // A full-order body has no stress modes: by default its series shows displacements only.
      const bool full = scene.system.model(body).sparse != nullptr;
      if (full && stresses && paraview["stresses"])
        r.fail(paraview["stresses"],
               fmt::format("paraview: body '{}' is modes: full, whose stresses fbsim does not recover "
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
    read_cadence(r, paraview, "paraview", "every", "interval", automatic, scene.paraview_every,
                 scene.paraview_interval);
  }
}

}  // namespace flexbody::scene
