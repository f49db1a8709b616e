#include "flexbody/preprocess/body_spec.hpp"

#include "flexbody/format/yaml_reader.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <stdexcept>
#include <system_error>

namespace flexbody::preprocess {
namespace {

using Reader = format::YamlReader;

Selector read_selector(const Reader& r, const YAML::Node& select, const std::string& where) {
  r.expect_map(select, where + " select", {"plane", "cylinder", "box", "surfaces", "group"});
  if (select.size() != 1)
    r.fail(select, fmt::format("{} select needs exactly one of plane, cylinder, box, surfaces, group", where));
  const auto entry = select.begin();
  const std::string kind = entry->first.Scalar();
  const YAML::Node s = entry->second;  // nodes are handles: copies are cheap and never dangle
  const std::string what = fmt::format("{} {}", where, kind);
  if (kind == "plane") {
    r.expect_map(s, what, {"point", "normal", "tolerance"});
    PlaneSelector plane{r.vector3(r.required(s, "point", what), what + " point"),
                        r.vector3(r.required(s, "normal", what), what + " normal"), 0.0};
    if (s["tolerance"]) plane.tolerance = r.positive(s["tolerance"], what + " tolerance");
    return plane;
  }
  if (kind == "cylinder") {
    r.expect_map(s, what, {"point", "direction", "radius", "tolerance"});
    CylinderSelector cylinder{r.vector3(r.required(s, "point", what), what + " point"),
                              r.vector3(r.required(s, "direction", what), what + " direction"),
                              r.positive(r.required(s, "radius", what), what + " radius"), 0.0};
    if (s["tolerance"]) cylinder.tolerance = r.positive(s["tolerance"], what + " tolerance");
    return cylinder;
  }
  if (kind == "box") {
    r.expect_map(s, what, {"min", "max"});
    return BoxSelector{r.vector3(r.required(s, "min", what), what + " min"),
                       r.vector3(r.required(s, "max", what), what + " max")};
  }
  if (kind == "surfaces") {
    if (!s.IsSequence() || s.size() == 0) r.fail(s, fmt::format("{} must be a list of surface tags", what));
    SurfaceSelector surfaces;
    for (std::size_t k = 0; k < s.size(); ++k) {
      const int tag = r.count(s[k], what + " tag");
      if (tag < 1) r.fail(s[k], fmt::format("{} tags start at 1, got {}", what, tag));
      surfaces.tags.push_back(tag);
    }
    return surfaces;
  }
  return GroupSelector{r.text(s, what)};  // "group": a physical group's name
}

}  // namespace

bool is_body_spec(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  return ext == ".yaml" || ext == ".yml";
}

PrepOptions read_body_spec(const std::filesystem::path& spec) {
  const std::string file = spec.string();
  if (std::error_code error; std::filesystem::is_directory(spec, error) || !std::ifstream(spec))
    throw std::invalid_argument(fmt::format("{}: cannot open the body spec: {}", file, Reader::why_unreadable(file)));
  YAML::Node loaded;
  try {
    loaded = YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(fmt::format("{}:{}: {}", file, e.mark.line + 1, e.msg));
  }
  PrepOptions options = read_body_spec(loaded, file, spec.parent_path());
  options.spec = spec;
  return options;
}

PrepOptions read_body_spec(const YAML::Node& loaded, const std::string& file, const std::filesystem::path& base) {
  const Reader r(file);
  const YAML::Node& root = loaded;  // const: operator[] never adds keys
  r.expect_map(root, "the body spec",
               {"input", "unit", "material", "mesh", "reduction", "interfaces", "load_points", "output_regions",
                "geometric_stiffness"});
  PrepOptions options;
  auto& recorded = options.recorded_options;
  recorded.emplace_back("spec", file);

  const std::string input = r.text(r.required(root, "input", "the body spec"), "input");
  options.input = std::filesystem::path(input).is_absolute() ? std::filesystem::path(input) : base / input;
  recorded.emplace_back("input", options.input.string());
  if (const YAML::Node unit = root["unit"]) {
    const std::string text = r.text(unit, "unit");
    options.mesh.unit = length_unit_from_string(text);
    if (!options.mesh.unit) r.fail(unit, fmt::format("unit '{}' is not one of mm, cm, m, in", text));
    options.mesh.unit_source = "the body spec's unit: " + text;
    recorded.emplace_back("unit", text);
  }
  if (const YAML::Node material = root["material"]) {
    if (material.IsScalar()) {
      try {
        options.material = parse_material(material.Scalar());
      } catch (const std::exception& e) {
        r.fail(material, e.what());
      }
    } else {
      r.expect_map(material, "material", {"E", "nu", "rho"});
      options.material = Material{"custom", r.number(r.required(material, "E", "material"), "material E"),
                                  r.number(r.required(material, "nu", "material"), "material nu"),
                                  r.number(r.required(material, "rho", "material"), "material rho")};
      try {
        check_material(options.material);
      } catch (const std::exception& e) {
        r.fail(material, e.what());
      }
    }
    recorded.emplace_back("material", fmt::format("{} E={} nu={} rho={}", options.material.name,
                                                  options.material.youngs_modulus, options.material.poisson_ratio,
                                                  options.material.density));
  }
  if (const YAML::Node mesh = root["mesh"]) {
    r.expect_map(mesh, "mesh", {"size", "order", "algorithm", "volume_tolerance", "thin_features", "error_target"});
    if (mesh["error_target"]) {
      options.error_target = r.number(mesh["error_target"], "mesh error_target");
      if (!(options.error_target >= 0.0 && options.error_target < 1.0))
        r.fail(mesh["error_target"], fmt::format("mesh error_target {} is a relative frequency error in [0, 1) (0.05: "
                                                 "5 %; 0: no refinement)", options.error_target));
      recorded.emplace_back("error_target", fmt::format("{}", options.error_target));
    }
    if (mesh["size"]) options.mesh.mesh_size = r.positive(mesh["size"], "mesh size");
    if (mesh["thin_features"]) {
      options.mesh.thin_feature_elements = r.positive(mesh["thin_features"], "mesh thin_features");
      recorded.emplace_back("thin_features", fmt::format("{}", options.mesh.thin_feature_elements));
    }
    if (mesh["volume_tolerance"]) {
      options.mesh.volume_tolerance = r.positive(mesh["volume_tolerance"], "mesh volume_tolerance");
      if (!(options.mesh.volume_tolerance < 1.0))
        r.fail(mesh["volume_tolerance"], fmt::format("mesh volume_tolerance {} is a fraction of the CAD volume below 1 "
                                                     "(0.005: 0.5 %)", options.mesh.volume_tolerance));
    }
    if (mesh["order"]) {
      const int order = r.count(mesh["order"], "mesh order");
      if (order != 1 && order != 2)
        r.fail(mesh["order"], fmt::format("mesh order {}: the element order is 1 (linear tetrahedra) or 2 (quadratic, "
                                          "10 nodes)", order));
      options.mesh.order = order;
    }
    if (mesh["algorithm"]) {
      const std::string text = r.text(mesh["algorithm"], "mesh algorithm");
      const std::optional<MeshAlgorithm> algorithm = mesh_algorithm_from_string(text);
      if (!algorithm) r.fail(mesh["algorithm"], fmt::format("mesh algorithm '{}' is unknown; use delaunay or hxt", text));
      options.mesh.algorithm = *algorithm;
    }
    recorded.emplace_back("mesh_size", fmt::format("{}", options.mesh.mesh_size));
  }
  options.modes.modes = 10;
  if (const YAML::Node reduction = root["reduction"]) {
    r.expect_map(reduction, "reduction", {"kind", "modes", "fmax", "eigensolver"});
    if (const YAML::Node kind = reduction["kind"]) {
      const std::string k = r.text(kind, "reduction kind");
      if (k == "craig-bampton") options.reduction = ReductionKind::craig_bampton;
      else if (k != "free-free") r.fail(kind, fmt::format("reduction kind '{}' is unknown; use free-free or craig-bampton", k));
    }
    const bool has_modes = static_cast<bool>(reduction["modes"]), has_fmax = static_cast<bool>(reduction["fmax"]);
    options.modes.modes = has_modes ? r.count(reduction["modes"], "reduction modes") : (has_fmax ? 0 : 10);
    if (has_modes && options.modes.modes < 1) r.fail(reduction["modes"], "reduction modes must be at least 1");
    if (has_fmax) options.modes.fmax_hz = r.positive(reduction["fmax"], "reduction fmax");
    if (const YAML::Node solver = reduction["eigensolver"]) {
      try {
        options.modes.solver.backend = eigensolver_backend_from_string(r.text(solver, "reduction eigensolver"));
      } catch (const std::invalid_argument& e) {
        r.fail(solver, e.what());
      }
    }
  }
  if (const YAML::Node geometric = root["geometric_stiffness"])
    options.geometric_stiffness = r.truth(geometric, "geometric_stiffness");
  recorded.emplace_back("geometric_stiffness", options.geometric_stiffness ? "true" : "false");
  recorded.emplace_back("reduction", std::string(to_string(options.reduction)));
  recorded.emplace_back("modes", std::to_string(options.modes.modes));
  recorded.emplace_back("fmax", fmt::format("{}", options.modes.fmax_hz));
  recorded.emplace_back("eigensolver", std::string(to_string(options.modes.solver.backend)));
  if (const YAML::Node interfaces = root["interfaces"]) {
    if (!interfaces.IsMap()) r.fail(interfaces, "interfaces must be a map of names to interfaces");
    std::set<std::string> names;
    for (auto it = interfaces.begin(); it != interfaces.end(); ++it) {
      const std::string name = it->first.Scalar();
      if (!names.insert(name).second) r.fail(it->first, fmt::format("interface '{}' is defined twice", name));
      const std::string where = fmt::format("interface '{}'", name);
      r.expect_map(it->second, where, {"select", "coupling"});
      InterfaceRequest request;
      request.name = name;
      request.select = read_selector(r, r.required(it->second, "select", where), where);
      if (const YAML::Node coupling = it->second["coupling"]) {
        request.coupling = r.text(coupling, where + " coupling");
        if (request.coupling != "rbe2" && request.coupling != "rbe3")
          r.fail(coupling, fmt::format("{}: coupling '{}' is unknown; use rbe2 or rbe3", where, request.coupling));
      }
      options.interfaces.push_back(std::move(request));
    }
    std::string list;
    for (const auto& i : options.interfaces) list += (list.empty() ? "" : " ") + i.name + ":" + i.coupling;
    recorded.emplace_back("interfaces", list);
  }
  std::set<std::string> marker_names;
  for (const InterfaceRequest& i : options.interfaces) marker_names.insert(i.name);
  if (const YAML::Node points = root["load_points"]) {
    if (!points.IsMap()) r.fail(points, "load_points must be a map of names to load points");
    for (auto it = points.begin(); it != points.end(); ++it) {
      const std::string name = it->first.Scalar();
      if (!marker_names.insert(name).second)
        r.fail(it->first, fmt::format("load point '{}': the name is already an interface or load point", name));
      const std::string where = fmt::format("load point '{}'", name);
      r.expect_map(it->second, where, {"select", "loads"});
      LoadPointRequest request;
      request.name = name;
      request.select = read_selector(r, r.required(it->second, "select", where), where);
      if (const YAML::Node loads = it->second["loads"]) {
        if (!loads.IsSequence() || loads.size() == 0)
          r.fail(loads, fmt::format("{} loads must be a list of fx, fy, fz, mx, my, mz", where));
        request.loads.fill(false);
        for (std::size_t k = 0; k < loads.size(); ++k) {
          const std::string load = r.text(loads[k], where + " load");
          const auto* found = std::find(kUnitLoadNames.begin(), kUnitLoadNames.end(), load);
          if (found == kUnitLoadNames.end())
            r.fail(loads[k], fmt::format("{}: load '{}' is unknown; use fx, fy, fz, mx, my, mz", where, load));
          auto& on = request.loads[static_cast<std::size_t>(found - kUnitLoadNames.begin())];
          if (on) r.fail(loads[k], fmt::format("{}: load '{}' is listed twice", where, load));
          on = true;
        }
      }
      options.load_points.push_back(std::move(request));
    }
    std::string list;
    for (const LoadPointRequest& p : options.load_points) {
      list += (list.empty() ? "" : " ") + p.name + ":";
      bool first = true;
      for (std::size_t k = 0; k < 6; ++k)
        if (p.loads[k]) {
          if (!first) list += '+';
          list += kUnitLoadNames[k];
          first = false;
        }
    }
    recorded.emplace_back("load_points", list);
  }
  if (const YAML::Node regions = root["output_regions"]) {
    // An empty map asks for no stress recovery at all (overriding the whole-body default of small meshes).
    if (!regions.IsMap()) r.fail(regions, "output_regions must be a map of names to regions (or {} for none)");
    std::vector<OutputRegionRequest> requests;
    for (auto it = regions.begin(); it != regions.end(); ++it) {
      const std::string name = it->first.Scalar();
      const std::string where = fmt::format("output region '{}'", name);
      if (name.empty() || name.find_first_of("/,") != std::string::npos || name == "order" || name == "stress_components")
        r.fail(it->first, fmt::format("{}: the name is not allowed (non-empty, no '/' or ',', not order or "
                                      "stress_components)", where));
      for (const OutputRegionRequest& other : requests)
        if (other.name == name) r.fail(it->first, fmt::format("{} is defined twice", where));
      r.expect_map(it->second, where, {"select"});
      const YAML::Node select = r.required(it->second, "select", where);
      OutputRegionRequest request;
      request.name = name;
      if (select.IsScalar()) {
        if (select.Scalar() != "all" && select.Scalar() != "surface")
          r.fail(select, fmt::format("{} select must be a selector map, 'all' (every node) or 'surface' (every boundary "
                                     "node), got '{}'", where, select.Scalar()));
        request.surface = select.Scalar() == "surface";
      } else {
        request.select = read_selector(r, select, where);
      }
      requests.push_back(std::move(request));
    }
    std::string list;
    for (const OutputRegionRequest& q : requests) list += (list.empty() ? "" : " ") + q.name;
    recorded.emplace_back("output_regions", list.empty() ? "none" : list);
    options.output_regions = std::move(requests);
  }
  return options;
}

void record_option(PrepOptions& options, const std::string& name, const std::string& value) {
  for (auto& [key, old] : options.recorded_options)
    if (key == name) {
      old = value;
      return;
    }
  options.recorded_options.emplace_back(name, value);
}

void record_resolved_options(PrepOptions& options) {
  record_option(options, "output", options.output.string());
  record_option(options, "volume_tolerance", fmt::format("{}", options.mesh.volume_tolerance));
  record_option(options, "element_order", options.mesh.order ? std::to_string(*options.mesh.order) : std::string("default"));
  record_option(options, "mesher", std::string(to_string(options.mesh.algorithm)));
  record_option(options, "modes", std::to_string(options.modes.modes));
  record_option(options, "fmax", fmt::format("{}", options.modes.fmax_hz));
  record_option(options, "geometric_stiffness", options.geometric_stiffness ? "true" : "false");
}

}  // namespace flexbody::preprocess
