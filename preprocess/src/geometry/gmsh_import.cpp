#include "flexbody/preprocess/gmsh_import.hpp"

#include "flexbody/format/tet10_element.hpp"
#include "flexbody/preprocess/curved_mesh_repair.hpp"
#include "flexbody/preprocess/mesh_topology.hpp"
#include "gmsh_meshing.hpp"
#include "gmsh_session.hpp"
#include "shell_sewing.hpp"
#include "step_unit.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <unordered_map>

namespace flexbody::preprocess {
namespace {

using detail::cad_surfaces;
using detail::estimated_elements;
using detail::GmshTetrahedra;
using detail::kGmshTet10;
using detail::measure;
using detail::mesh_resolving_the_volume;
using detail::tetrahedra_from_gmsh;
using detail::UnitDecision;

// Refuse a mesh size that would give more tetrahedra than this: 2e7 tets are ~1e7 DOFs, several times
// what fits in 24 GiB, and such a request is nearly always a unit mistake.
constexpr double kMaxEstimatedElements = 2e7;
// A part smaller than this across, in gmsh's own coordinates, is where gmsh's and OpenCASCADE's absolute
// tolerances start to spoil the mesh (see import_tet_mesh): 1e-2 of the file's unit.
constexpr double kSmallInModelUnits = 1e-2;
// Faces closer than this fraction of the part's bounding-box diagonal are sewn together (shell_sewing.hpp):
// OpenCASCADE's sewing tolerance, relative so that a part sews the same in any unit.
constexpr double kSewingTolerance = 1e-6;
// Parts outside this extent [m] (bounding-box diagonal) are named in a warning before the work: nearly always a unit
// mistake (a part 4 µm across failed in the eigensolver, which blamed itself).
constexpr double kPlausibleExtent[2] = {1e-4, 1e3};

// The CAD solids' volume in gmsh's coordinates (OpenCASCADE's mass properties), or nullopt for a model that is not
// OpenCASCADE's (a .geo in gmsh's built-in kernel) or has no positive volume.
std::optional<double> cad_volume(const gmsh::vectorpair& volumes) {
  double total = 0.0;
  try {
    detail::SilencedStdStreams quiet;
    for (const auto& [dim, tag] : volumes) {
      double mass = 0.0;
      gmsh::model::occ::getMass(dim, tag, mass);
      total += mass;
    }
  } catch (const std::string&) {
    return std::nullopt;
  }
  return total > 0.0 && std::isfinite(total) ? std::optional<double>(total) : std::nullopt;
}

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// "millimetres", "metres", ...: the unit's name in a sentence.
std::string_view plural_name(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::millimetre: return "millimetres";
    case LengthUnit::centimetre: return "centimetres";
    case LengthUnit::metre: return "metres";
    case LengthUnit::inch: return "inches";
  }
  return "?";
}

// The rule: a unit the user gives is the unit of the file's numbers and wins over a STEP file's
// declaration; without one, the declaration holds. OpenCASCADE has already converted the declared unit
// to mm (a STEP file without a LENGTH_UNIT is taken as mm), so gmsh's coordinate is the file's number
// times (declared unit / mm), and the override is a plain factor: that conversion undone, times the
// user's unit. Every length the user gives (mesh size, a spec's selectors) is in geometry_unit.
UnitDecision decide_unit(const std::filesystem::path& path, InputFormat format, std::optional<LengthUnit> unit,
                         const std::string& unit_source) {
  const std::string name = path.filename().string();
  const std::string source = unit ? (unit_source.empty() ? fmt::format("--unit {}", to_string(*unit)) : unit_source)
                                  : std::string();
  if (format == InputFormat::iges) {
    if (unit)
      throw std::invalid_argument(fmt::format(
          "{}: fbprep does not read the unit an IGES file declares (OpenCASCADE converts it to mm), so {} cannot "
          "be applied; drop it to read the file as it declares (lengths then in mm), or export the part as STEP",
          name, source));
    return UnitDecision{LengthUnit::millimetre, std::nullopt, false, 1e-3, 1.0,
                        "IGES: OpenCASCADE converts the file's declared unit to mm (fbprep does not read IGES "
                        "headers)"};
  }
  if (format == InputFormat::step) {
    const detail::StepLengthUnit step = detail::declared_step_unit(path);
    if (step.declared && !step.unit) {
      if (unit)
        throw std::invalid_argument(fmt::format(
            "{}: the STEP file declares a length unit fbprep does not read (OpenCASCADE converts it to mm), so {} "
            "cannot override it; drop it to read the file as it declares (lengths then in mm)", name, source));
      return UnitDecision{LengthUnit::millimetre, std::nullopt, false, 1e-3, 1.0,
                          "the STEP file declares a length unit other than mm, cm, m, in; OpenCASCADE converts it "
                          "to mm"};
    }
    // What OpenCASCADE did: file number x occ_factor = gmsh coordinate (mm).
    const LengthUnit occ_source = step.unit.value_or(LengthUnit::millimetre);
    const double occ_factor = metres_per(occ_source) / 1e-3;
    UnitDecision d{unit.value_or(occ_source), step.unit, false, 0.0, occ_factor, ""};
    d.gmsh_to_metres = d.geometry_unit == occ_source ? 1e-3 : metres_per(d.geometry_unit) / occ_factor;
    if (!step.declared && unit)
      d.reason = fmt::format("the STEP file declares no length unit; {}: coordinates read as {}", source,
                             plural_name(*unit));
    else if (!step.declared)
      d.reason = "the STEP file declares no length unit; read as mm (OpenCASCADE's default; --unit chooses another)";
    else if (!unit)
      d.reason = fmt::format("declared in the STEP file ({}); OpenCASCADE converts it to mm", to_string(*step.unit));
    else if (*unit == *step.unit)
      d.reason = fmt::format("declared in the STEP file ({}); {} agrees", to_string(*step.unit), source);
    else {
      d.overrides = true;
      d.reason = fmt::format("the STEP file declares {}; {} overrides it: coordinates read as {}",
                             to_string(*step.unit), source, plural_name(*unit));
    }
    return d;
  }
  if (!unit)
    throw std::runtime_error(fmt::format("{}: {} files carry no length unit; pass --unit mm|cm|m|in", name,
                                         to_string(format)));
  return UnitDecision{*unit, std::nullopt, false, metres_per(*unit), 1.0,
                      fmt::format("{} carries no unit; {}: coordinates read as {}", to_string(format), source,
                                  plural_name(*unit))};
}

void check_readable(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw std::runtime_error(fmt::format("{}: no such file", path.string()));
  if (std::filesystem::is_directory(path, ec))
    throw std::runtime_error(fmt::format("{}: is a directory, not a file", path.string()));
  errno = 0;
  std::FILE* probe = std::fopen(path.c_str(), "rb");
  if (probe == nullptr)
    throw std::runtime_error(fmt::format("{}: cannot be opened for reading: {}", path.string(),
                                         std::generic_category().message(errno)));
  std::fclose(probe);
}

// The order of a ready mesh's tetrahedra, when none was asked for: the kind it holds (neither: 1, whose reading then
// says that the mesh has no tetrahedra; both: refused when read).
int order_of_msh() {
  std::vector<int> types;
  gmsh::model::mesh::getElementTypes(types);
  return std::find(types.begin(), types.end(), kGmshTet10) != types.end() ? 2 : 1;
}

// Points, curves and faces of the model that bound nothing of a higher dimension, when it has a solid (a model of
// faces only has none: its faces are what sewing works on).
std::array<int, 3> loose_entities() {
  std::array<int, 3> loose{0, 0, 0};
  gmsh::vectorpair volumes;
  gmsh::model::getEntities(volumes, 3);
  if (volumes.empty()) return loose;
  for (int dim = 0; dim < 3; ++dim) {
    gmsh::vectorpair entities;
    gmsh::model::getEntities(entities, dim);
    for (const auto& [d, tag] : entities) {
      std::vector<int> up, down;
      gmsh::model::getAdjacencies(d, tag, up, down);
      if (up.empty()) ++loose[static_cast<std::size_t>(dim)];
    }
  }
  return loose;
}

}  // namespace

std::string_view to_string(InputFormat format) {
  switch (format) {
    case InputFormat::step: return "STEP";
    case InputFormat::iges: return "IGES";
    case InputFormat::brep: return "BREP";
    case InputFormat::geo: return "gmsh .geo";
    case InputFormat::msh: return "gmsh .msh";
  }
  return "?";
}

std::string_view to_string(MeshAlgorithm algorithm) {
  return algorithm == MeshAlgorithm::hxt ? "hxt" : "delaunay";
}

std::optional<MeshAlgorithm> mesh_algorithm_from_string(std::string_view text) {
  if (text == "delaunay") return MeshAlgorithm::delaunay;
  if (text == "hxt") return MeshAlgorithm::hxt;
  return std::nullopt;
}

InputFormat input_format_of(const std::filesystem::path& path) {
  const std::string ext = lowercase(path.extension().string());
  if (ext == ".step" || ext == ".stp") return InputFormat::step;
  if (ext == ".iges" || ext == ".igs") return InputFormat::iges;
  if (ext == ".brep") return InputFormat::brep;
  if (ext == ".geo") return InputFormat::geo;
  if (ext == ".msh") return InputFormat::msh;
  throw std::invalid_argument(fmt::format("{}: unsupported file type '{}'; use .step/.stp, .iges/.igs, .brep, "
                                          ".geo or .msh", path.string(), ext));
}

ImportedMesh import_tet_mesh(const std::filesystem::path& path, const GmshImportOptions& options) {
  const std::string name = path.filename().string();
  ImportedMesh result;
  result.format = input_format_of(path);
  check_readable(path);
  if (options.order && *options.order != 1 && *options.order != 2)
    throw std::invalid_argument(fmt::format("element order {}: the element order is 1 (linear tetrahedra) or 2 "
                                            "(quadratic)", *options.order));
  if (!(options.mesh_size >= 0.0) || !std::isfinite(options.mesh_size))
    throw std::invalid_argument(fmt::format("--mesh-size must be a positive length, got {}", options.mesh_size));
  if (!(options.thin_feature_elements >= 0.0) || !std::isfinite(options.thin_feature_elements))
    throw std::invalid_argument(fmt::format("--thin-features must be a positive number of elements, got {}",
                                            options.thin_feature_elements));
  if (options.size_field && result.format == InputFormat::msh)
    throw std::invalid_argument(fmt::format("{}: a size field sizes a mesh fbprep makes; a .msh is used as it is",
                                            path.filename().string()));
  if (options.thin_feature_elements > 0.0 && result.format == InputFormat::msh)
    throw std::invalid_argument(fmt::format("{}: --thin-features sizes a mesh fbprep makes; a .msh is used as it is",
                                            path.filename().string()));
  const UnitDecision unit = decide_unit(path, result.format, options.unit, options.unit_source);
  result.unit = unit.geometry_unit;
  result.unit_reason = unit.reason;
  result.declared_unit = unit.declared;
  result.unit_overrides_declared = unit.overrides;

  detail::GmshSession session;
  if (options.progress) options.progress("reading " + name);
  {
    detail::SilencedStdStreams quiet;
    detail::gmsh_call(name, [&] {
      if (result.format == InputFormat::geo || result.format == InputFormat::msh) {
        gmsh::open(path.string());
      } else {
        // Everything the file holds, to count what lies beside the solids (loose faces, curves, points), which
        // the part is meshed without: read once more with the highest dimension only when there is any.
        gmsh::model::add("part");
        gmsh::vectorpair imported;
        gmsh::model::occ::importShapes(path.string(), imported, /*highestDimOnly=*/false);
        gmsh::model::occ::synchronize();
        result.loose_entities = loose_entities();
        if (result.loose_entities[0] + result.loose_entities[1] + result.loose_entities[2] > 0) {
          gmsh::clear();
          gmsh::model::add("part");
          gmsh::model::occ::importShapes(path.string(), imported, /*highestDimOnly=*/true);
          gmsh::model::occ::synchronize();
        }
      }
    });
  }

  GmshTetrahedra tetrahedra;
  if (result.format == InputFormat::msh) {
    result.meshed_here = false;
  } else detail::gmsh_call(name, [&] {
    gmsh::vectorpair volumes, surfaces;
    gmsh::model::getEntities(volumes, 3);
    gmsh::model::getEntities(surfaces, 2);
    double xmin, ymin, zmin, xmax, ymax, zmax;
    gmsh::model::getBoundingBox(-1, -1, xmin, ymin, zmin, xmax, ymax, zmax);
    const double diagonal = std::hypot(xmax - xmin, ymax - ymin, zmax - zmin);
    const bool cad = result.format == InputFormat::step || result.format == InputFormat::iges ||
                     result.format == InputFormat::brep;
    if (volumes.empty() && cad && !surfaces.empty()) {  // faces only: sewn into a solid if they close one
      if (options.progress)
        options.progress(fmt::format("the input has no volume: sewing its {} faces into a solid (OpenCASCADE)",
                                     surfaces.size()));
      const detail::SewingOutcome sewn = detail::sew_shells_into_solids(kSewingTolerance * diagonal);
      // One closed shell is one solid; closed shells side by side are an assembly, like several solids.
      if (sewn.free_edges > 0 || sewn.solids == 0)
        throw std::runtime_error(fmt::format(
            "{}: the input has no volume ({} surfaces), and sewing them made no closed solid: {} free edges (each "
            "bounds one face only) leave {} shell(s) open (sewing tolerance {:.3g} m); fbprep needs a closed solid",
            name, sewn.surfaces, sewn.free_edges, sewn.shells, kSewingTolerance * diagonal * unit.gmsh_to_metres));
      if (sewn.shells > 1)
        throw std::runtime_error(fmt::format(
            "{}: the input has no volume ({} surfaces); sewn, they make {} closed shells: an assembly is not one body "
            "(export each part on its own, or fuse them in CAD)", name, sewn.surfaces, sewn.shells));
      result.sewn_faces = sewn.surfaces;
      gmsh::model::getEntities(volumes, 3);
      gmsh::model::getEntities(surfaces, 2);
    }
    result.volumes = static_cast<int>(volumes.size());
    if (volumes.empty())
      throw std::runtime_error(fmt::format("{}: the input has no volume ({} surfaces); fbprep needs a solid", name,
                                           surfaces.size()));
    result.extent_m = diagonal * unit.gmsh_to_metres;
    if (!(result.extent_m >= kPlausibleExtent[0] && result.extent_m <= kPlausibleExtent[1])) {
      result.size_warning = fmt::format("the part is {:.3g} m across (bounding-box diagonal), read in {}: {}; check the "
                                        "unit ({})", result.extent_m, plural_name(unit.geometry_unit),
                                        result.extent_m < kPlausibleExtent[0] ? "smaller than 0.1 mm"
                                                                             : "larger than 1 km",
                                        unit.reason);
      if (options.warning) options.warning(result.size_warning);
    }
    const double size = options.mesh_size > 0.0 ? options.mesh_size * unit.size_unit_to_gmsh : diagonal / 25.0;
    result.mesh_size_m = size * unit.gmsh_to_metres;
    const std::optional<double> solid_volume = cad_volume(volumes);
    if (solid_volume) result.cad_volume_m3 = *solid_volume * std::pow(unit.gmsh_to_metres, 3);
    const double elements =
        estimated_elements(solid_volume.value_or((xmax - xmin) * (ymax - ymin) * (zmax - zmin)), size);
    if (elements > kMaxEstimatedElements)
      throw std::invalid_argument(fmt::format(
          "{}: element size {:.4g} m would give about {:.2g} tetrahedra for a part of {:.4g} x {:.4g} x {:.4g} m "
          "(limit {:.0e}); check --unit and --mesh-size", name, result.mesh_size_m, elements,
          (xmax - xmin) * unit.gmsh_to_metres, (ymax - ymin) * unit.gmsh_to_metres, (zmax - zmin) * unit.gmsh_to_metres,
          kMaxEstimatedElements));
    gmsh::option::setNumber("Mesh.ElementOrder", 1);
    gmsh::option::setNumber("Mesh.Optimize", 1);
    if (options.algorithm == MeshAlgorithm::hxt) {  // parallel Delaunay refinement on the process' threads
      gmsh::option::setNumber("Mesh.Algorithm3D", 10);
      // gmsh 4.8 takes HXT's thread count from General.NumThreads (1 since initialize); Mesh.MaxNumThreads3D can only
      // lower it. The session gives OpenMP the process' count back when it ends.
      gmsh::option::setNumber("General.NumThreads", session.threads());
      gmsh::option::setNumber("Mesh.MaxNumThreads1D", 1);  // curves and surfaces as with the default mesher
      gmsh::option::setNumber("Mesh.MaxNumThreads2D", 1);
    }
    GmshImportOptions resolved = options;  // the inner steps read the order it resolves to
    resolved.order = options.order.value_or(kDefaultElementOrder);
    tetrahedra = mesh_resolving_the_volume(name, size, solid_volume, unit, resolved, result, elements);
  });
  int order = options.order.value_or(kDefaultElementOrder);
  if (result.format == InputFormat::msh)
    detail::gmsh_call(name, [&] {
      if (!options.order) order = order_of_msh();
      tetrahedra = tetrahedra_from_gmsh(name, order);
    });
  detail::gmsh_call(name, [&] {
    result.mesh = std::move(tetrahedra.mesh);
    result.quadratic = std::move(tetrahedra.quadratic);
    result.surfaces = cad_surfaces(tetrahedra.index_of_tag, order);
  });
  result.mesh.nodes *= unit.gmsh_to_metres;
  if (result.quadratic) result.quadratic->nodes *= unit.gmsh_to_metres;

  const MeshComponents components = connected_components(result.mesh);
  if (components.count > 1)
    throw std::runtime_error(fmt::format("{}: found {} disconnected solids; an assembly is not one body (export "
                                         "each part on its own, or fuse them in CAD)", name, components.count));
  try {
    check_element_volumes(result.mesh, name);
  } catch (const std::runtime_error& e) {
    // gmsh and OpenCASCADE work to absolute tolerances in the file's own numbers. Measured with gmsh 4.8: the
    // sample bracket written in metres at 0.9 mm across gets a flat tetrahedron (its surface mesh has a node on
    // another triangle's edge), the same geometry at 2.7 mm, or at 0.9 mm written in millimetres, meshes
    // cleanly. A part under 1e-2 of the file's unit across is in that range: say how to get out of it.
    const double across = (result.mesh.nodes.colwise().maxCoeff() - result.mesh.nodes.colwise().minCoeff()).norm() /
                          unit.gmsh_to_metres;
    if (result.meshed_here && across < kSmallInModelUnits)
      throw std::runtime_error(fmt::format(
          "{}; the part is only {:.3g} across in gmsh's coordinates (the file's numbers; mm for STEP and IGES), "
          "where gmsh and OpenCASCADE work to fixed absolute tolerances: write a part this small in mm and pass "
          "--unit mm", e.what(), across));
    throw;
  }
  // What gmsh's smoothing left folded, straightened (its corners' tetrahedra are positive: checked just above).
  if (result.curved_repair && result.curved_repair->left() > 0) {
    const auto start = std::chrono::steady_clock::now();
    result.curved_repair->straightened = straighten_folded_elements(*result.quadratic);
    result.curved_repair->seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  measure(result.surfaces, result.quadratic ? result.quadratic->nodes : result.mesh.nodes);
  if (result.quadratic) {  // curved elements: det ∂x/∂ξ > 0 at every Gauss point and node (tet10_element.hpp)
    // A mesh made here has been repaired above; a .msh's elements are the user's, used as they are.
    const std::vector<Eigen::Index> folded = folded_elements(*result.quadratic);
    if (!folded.empty())
      throw std::runtime_error(fmt::format("{}: {} of {} quadratic tetrahedra are folded by their curved edges (Jacobian "
                                           "determinant not positive at a Gauss point or node; the first is element "
                                           "{})", name, folded.size(), result.quadratic->element_count(), folded.front()));
  }
  return result;
}

}  // namespace flexbody::preprocess
