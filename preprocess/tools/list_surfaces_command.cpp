// list_surfaces_command.cpp: `fbprep list-surfaces INPUT [--unit U] [--mesh-size L] [--json]`: the CAD
// surfaces of a part by tag, with area, centroid and physical groups, for `select: {surfaces: [...]}` in a
// body spec. The part is meshed as fbprep would mesh it, so the areas are those of the faceted surfaces
// that interfaces use.
#include "cli_common.hpp"

#include "flexbody/preprocess/gmsh_import.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <iostream>

namespace flexbody::cli {

int list_surfaces_command(int argc, char** argv) {
  CLI::App app{"fbprep list-surfaces: the CAD surfaces of a part (tag, area, centroid, physical groups), for "
               "interfaces selected by surface tag in a body spec."};
  app.name("fbprep list-surfaces");
  std::string input, unit_text;
  double mesh_size = 0.0;
  int order = 1;
  bool json = false;
  app.add_option("INPUT", input, "STEP/STP, IGES/IGS, BREP, gmsh .geo or .msh")->required();
  app.add_option("--unit", unit_text, "unit of INPUT's coordinates, as for fbprep");
  app.add_option("--mesh-size", mesh_size, "element size in the input's unit, as for fbprep");
  app.add_option("--order", order, "element order 1 or 2, as for fbprep (default 2; a .msh: the order it holds)");
  app.add_flag("--json", json, "print one JSON object on stdout instead of the table");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail(std::string(e.what()) + " (see fbprep list-surfaces --help)", kBadCommandLine);
  }
  preprocess::GmshImportOptions options;
  try {
    if (!unit_text.empty()) {
      options.unit = preprocess::length_unit_from_string(unit_text);
      if (!options.unit) throw std::invalid_argument("--unit '" + unit_text + "' is not one of mm, cm, m, in");
    }
    if (app.count("--mesh-size") > 0 && !(std::isfinite(mesh_size) && mesh_size > 0.0))
      throw std::invalid_argument(fmt::format("--mesh-size must be a positive number (the largest element size in the "
                                              "input's unit; leave it out for the default), got {}", mesh_size));
    options.mesh_size = mesh_size;
    if (app.count("--order") > 0) options.order = order;
    const preprocess::ImportedMesh imported = preprocess::import_tet_mesh(input, options);
    if (json) {
      nlohmann::ordered_json j;
      j["input"] = input;
      j["length_unit"] = std::string(to_string(imported.unit));
      j["length_unit_reason"] = imported.unit_reason;
      j["declared_unit"] = imported.declared_unit ? nlohmann::ordered_json(std::string(to_string(*imported.declared_unit)))
                                                  : nlohmann::ordered_json(nullptr);
      j["surfaces"] = nlohmann::ordered_json::array();
      for (const auto& s : imported.surfaces)
        j["surfaces"].push_back({{"tag", s.tag},
                                 {"area_m2", s.area_m2},
                                 {"centroid_m", {s.centroid_m.x(), s.centroid_m.y(), s.centroid_m.z()}},
                                 {"groups", s.groups}});
      std::cout << j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
    } else {
      std::cout << fmt::format("{}: {} surfaces (SI units, input frame; read in {}: {})\n", input,
                               imported.surfaces.size(), to_string(imported.unit), imported.unit_reason)
                << fmt::format("  {:>5}  {:>14}  {:>38}  {}\n", "tag", "area [m^2]", "centroid [m]", "groups");
      for (const auto& s : imported.surfaces)
        std::cout << fmt::format("  {:>5}  {:>14.6g}  [{:>10.6g}, {:>10.6g}, {:>10.6g}]  {}\n", s.tag, s.area_m2,
                                 s.centroid_m.x(), s.centroid_m.y(), s.centroid_m.z(), fmt::join(s.groups, ", "));
    }
  } catch (const std::invalid_argument& e) {
    return fail(e.what(), kBadCommandLine);
  } catch (const std::exception& e) {
    return fail(e.what(), kFailed);
  }
  return 0;
}

}  // namespace flexbody::cli
