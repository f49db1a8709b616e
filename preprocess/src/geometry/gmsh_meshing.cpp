// gmsh_meshing.hpp: the model meshed at a size, folded quadratic elements smoothed, thin features and a refinement's
// sizes applied, the volume checked; the tetrahedra and the CAD surfaces read back.
#include "gmsh_meshing.hpp"

#include "flexbody/preprocess/curved_mesh_repair.hpp"
#include "flexbody/preprocess/mesh_topology.hpp"
#include "gmsh_session.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>

namespace flexbody::preprocess::detail {
namespace {

constexpr int kGmshTriangle3 = 2;  // the 3-node triangle
constexpr int kGmshTriangle6 = 9;  // the 6-node triangle of a second-order surface mesh
// Halvings of the element size tried when a mesh misses the CAD solid's volume (mesh_resolving_the_volume; the
// estimated tetrahedra beyond which no finer mesh is tried: GmshImportOptions::volume_search_elements). Measured on
// the corpus (bench/cad_corpus_bench.py): the one default linear mesh that needed four halvings was a curved solid of
// as1-tu-203 (64.4 % at 8 mm, 99.50 % at 1 mm, held at 0.5 mm).
constexpr int kVolumeRefinements = 4;

}  // namespace

GmshTetrahedra tetrahedra_from_gmsh(const std::string& name, int order) {
  const int type = order == 2 ? kGmshTet10 : kGmshTet4, per = order == 2 ? 10 : 4;
  std::vector<std::size_t> node_tags;
  std::vector<double> coordinates, parametric;
  gmsh::model::mesh::getNodes(node_tags, coordinates, parametric, -1, -1, /*includeBoundary=*/true, false);
  std::vector<std::size_t> element_tags, element_nodes;
  gmsh::model::mesh::getElementsByType(type, element_tags, element_nodes);
  std::vector<int> types;
  gmsh::model::mesh::getElementTypes(types);
  const int other = order == 2 ? kGmshTet4 : kGmshTet10;
  const bool has_other = std::find(types.begin(), types.end(), other) != types.end();
  if (!element_tags.empty() && has_other)  // reading one kind would drop the other's volumes
    throw std::runtime_error(fmt::format("{}: the mesh holds both linear and quadratic tetrahedra; fbprep reads one "
                                         "kind (mesh every volume in the same order)", name));
  if (element_tags.empty()) {
    throw std::runtime_error(fmt::format("{}: the mesh has no {} tetrahedra{}", name, order == 2 ? "quadratic" : "linear",
                                         has_other ? fmt::format(" (it has {} ones: ask for order {} to read them)",
                                                                 order == 2 ? "linear" : "quadratic", order == 2 ? 1 : 2)
                                                   : ""));
  }
  // Corners get indices in the order of gmsh's node list (as linear meshes always had), mid-edge nodes after them.
  enum : char { unused = 0, corner = 1, middle = 2 };
  std::unordered_map<std::size_t, char> role;
  role.reserve(node_tags.size());
  for (std::size_t k = 0; k < element_nodes.size(); ++k) {
    char& r = role[element_nodes[k]];
    const char now = static_cast<int>(k % static_cast<std::size_t>(per)) < 4 ? corner : middle;
    if (r != unused && r != now)  // only a malformed .msh can do this
      throw std::runtime_error(fmt::format("{}: node {} is a corner of one tetrahedron and a mid-edge node of another",
                                           name, element_nodes[k]));
    r = now;
  }
  std::unordered_map<std::size_t, std::int32_t> index;
  std::int32_t corners = 0, middles = 0;
  for (const std::size_t tag : node_tags) {  // a tag listed twice keeps its first index
    const auto it = role.find(tag);
    if (it != role.end() && it->second == corner && index.emplace(tag, corners).second) ++corners;
  }
  for (const std::size_t tag : node_tags) {
    const auto it = role.find(tag);
    if (it != role.end() && it->second == middle && index.emplace(tag, corners + middles).second) ++middles;
  }
  RowMatrixX3d nodes(corners + middles, 3);  // gmsh may list a node twice (with its boundary entities): same place
  for (std::size_t k = 0; k < node_tags.size(); ++k) {
    const auto it = index.find(node_tags[k]);
    if (it == index.end()) continue;
    for (int c = 0; c < 3; ++c) nodes(it->second, c) = coordinates[3 * k + static_cast<std::size_t>(c)];
  }
  const auto elements = static_cast<Eigen::Index>(element_tags.size());
  auto index_of = [&](Eigen::Index e, int local) {
    const std::size_t tag = element_nodes[static_cast<std::size_t>(per * e + local)];
    const auto it = index.find(tag);
    if (it == index.end())
      throw std::runtime_error(fmt::format("{}: tetrahedron {} refers to missing node {}", name,
                                           element_tags[static_cast<std::size_t>(e)], tag));
    return it->second;
  };
  GmshTetrahedra out;
  out.mesh.nodes = nodes.topRows(corners);
  out.mesh.tets.resize(elements, 4);
  for (Eigen::Index e = 0; e < elements; ++e)
    for (int a = 0; a < 4; ++a) out.mesh.tets(e, a) = index_of(e, a);
  if (order == 2) {
    constexpr int kFromGmsh[10] = {0, 1, 2, 3, 4, 5, 6, 7, 9, 8};  // our node k is gmsh's node kFromGmsh[k]
    Tet10Mesh quadratic;
    quadratic.nodes = std::move(nodes);
    quadratic.tets.resize(elements, 10);
    for (Eigen::Index e = 0; e < elements; ++e)
      for (int k = 0; k < 10; ++k) quadratic.tets(e, k) = index_of(e, kFromGmsh[k]);
    out.quadratic = std::move(quadratic);
  }
  out.index_of_tag = std::move(index);
  return out;
}

// Every surface entity's triangles in the tetrahedral mesh's numbering, with its physical groups. A second-order
// mesh's 6-node triangles (gmsh lists the corners, then the edges (0,1), (1,2), (2,0)) are split into their four
// triangles, as the body file's surface is (mesh_topology.hpp).
std::vector<CadSurface> cad_surfaces(const std::unordered_map<std::size_t, std::int32_t>& index_of_tag, int order) {
  const int type = order == 2 ? kGmshTriangle6 : kGmshTriangle3;
  const std::size_t per = order == 2 ? 6 : 3;
  gmsh::vectorpair entities;
  gmsh::model::getEntities(entities, 2);
  std::vector<CadSurface> surfaces;
  for (const auto& [dim, tag] : entities) {
    std::vector<std::size_t> element_tags, node_tags;
    gmsh::model::mesh::getElementsByType(type, element_tags, node_tags, tag);
    std::vector<std::array<std::int32_t, 3>> kept;
    for (std::size_t t = 0; t < element_tags.size(); ++t) {
      std::array<std::int32_t, 6> face{};
      bool ok = true;
      for (std::size_t a = 0; a < per; ++a) {
        const auto it = index_of_tag.find(node_tags[per * t + a]);
        ok = ok && it != index_of_tag.end();
        if (ok) face[a] = it->second;
      }
      if (!ok) continue;
      if (order == 2) {
        for (const auto& triangle : split_quadratic_triangle(face)) kept.push_back(triangle);
      } else {
        kept.push_back({face[0], face[1], face[2]});
      }
    }
    if (kept.empty()) continue;  // a surface inside no tetrahedron's boundary, or without a mesh
    CadSurface surface;
    surface.tag = tag;
    surface.triangles.resize(static_cast<Eigen::Index>(kept.size()), 3);
    for (std::size_t t = 0; t < kept.size(); ++t)
      for (int a = 0; a < 3; ++a) surface.triangles(static_cast<Eigen::Index>(t), a) = kept[t][static_cast<std::size_t>(a)];
    surfaces.push_back(std::move(surface));
  }
  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups, 2);
  for (const auto& [dim, group] : groups) {
    std::string name;
    gmsh::model::getPhysicalName(dim, group, name);
    if (name.empty()) name = fmt::format("{}", group);  // unnamed groups go by their number
    std::vector<int> members;
    gmsh::model::getEntitiesForPhysicalGroup(dim, group, members);
    for (CadSurface& surface : surfaces)
      if (std::find(members.begin(), members.end(), surface.tag) != members.end()) surface.groups.push_back(name);
  }
  return surfaces;
}

// Area and centroid of each surface's triangles (nodes in metres).
void measure(std::vector<CadSurface>& surfaces, const RowMatrixX3d& nodes) {
  for (CadSurface& surface : surfaces) {
    surface.area_m2 = 0.0;
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();
    for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t) {
      const Eigen::Vector3d a = nodes.row(surface.triangles(t, 0)), b = nodes.row(surface.triangles(t, 1)),
                            c = nodes.row(surface.triangles(t, 2));
      const double area = 0.5 * (b - a).cross(c - a).norm();
      surface.area_m2 += area;
      moment += area * (a + b + c) / 3.0;
    }
    surface.centroid_m = surface.area_m2 > 0.0 ? Eigen::Vector3d(moment / surface.area_m2) : moment;
  }
}

namespace {

// gmsh's elastic smoothing on a quadratic mesh with folded elements (curved_mesh_repair.hpp): the high-order nodes
// inside the volume follow the curved boundary as an elastic solid would ("HighOrderElastic"), then the tetrahedra
// are read again. Measured with gmsh 4.8 at the default size: it left 0 of 30 and 0 of 16 folded elements
// (SOT_323_3, TCMT1107_4), 7 of 63 (TSM_104_01_L_DV_A), 4 of 19 (0603_SMD) and 18 of 50 (MSOP_10), in 1.4-3 s, the same
// mesh in every run. gmsh's other optimizer, "HighOrder" (on the elements' scaled Jacobians), is not used: on 0603_SMD
// it took 27-44 s, gave a different mesh in each of three runs, and in two of them inverted corner tetrahedra;
// on MSOP_10 it failed ("Failed to reach critical value"). Straightening the rest moved nodes by at most 0.1-3 % of
// the element size on these parts (the report gives it).
CurvedElementRepair optimize_folded(const std::string& name, GmshTetrahedra& tetrahedra, const GmshImportOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  CurvedElementRepair repair;
  repair.elements = tetrahedra.quadratic->element_count();
  repair.folded = static_cast<Eigen::Index>(folded_elements(*tetrahedra.quadratic).size());
  const Eigen::Index left = repair.folded;
  if (left > 0) {
    if (options.progress)
      options.progress(fmt::format("{} of {} quadratic tetrahedra folded by their curved edges: gmsh's elastic "
                                   "smoothing", left, repair.elements));
    try {
      detail::SilencedStdStreams quiet;
      gmsh::model::mesh::optimize("HighOrderElastic");
    } catch (const std::string& message) {  // the mesh as the pass left it is still read: it may have improved
      repair.elastic_message = message;
    }
    tetrahedra = tetrahedra_from_gmsh(name, 2);
    repair.after_elastic = static_cast<Eigen::Index>(folded_elements(*tetrahedra.quadratic).size());
  }
  repair.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return repair;
}

// Each CAD point's element size: the shortest CAD curve through it over `across` (GmshImportOptions::
// thin_feature_elements), within [kThinFeatureFloor, 1] × `size`; gmsh interpolates point sizes along curves and over
// faces (Mesh.MeshSizeFromPoints and Mesh.MeshSizeExtendFromBoundary, both on by default).
void size_thin_features(double size, double across) {
  gmsh::vectorpair curves;
  gmsh::model::getEntities(curves, 1);
  std::map<int, double> sizes;  // by point tag
  for (const auto& curve : curves) {
    gmsh::vectorpair ends;
    gmsh::model::getBoundary({curve}, ends, false, false, false);
    double length = 0.0;
    try {  // OpenCASCADE's length; a .geo in gmsh's own kernel has none: the chord between the ends (shorter)
      detail::SilencedStdStreams quiet;
      gmsh::model::occ::getMass(1, curve.second, length);
    } catch (const std::string&) {
      std::vector<double> a, b;
      if (ends.size() == 2) {
        gmsh::model::getValue(0, std::abs(ends[0].second), {}, a);
        gmsh::model::getValue(0, std::abs(ends[1].second), {}, b);
        if (a.size() == 3 && b.size() == 3) length = std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
      }
    }
    if (!(length > 0.0)) continue;  // a closed curve without its length (built-in kernel): no measure of it
    for (const auto& end : ends) {
      const int tag = std::abs(end.second);
      const double at = std::clamp(length / across, kThinFeatureFloor * size, size);
      const auto [it, inserted] = sizes.emplace(tag, at);
      if (!inserted) it->second = std::min(it->second, at);
    }
  }
  for (const auto& [tag, at] : sizes)
    gmsh::model::mesh::setSize({{0, tag}}, at);
}

// GmshImportOptions::size_field as gmsh's background mesh: a list-based view of its tetrahedra ("SS": each with its
// corners' coordinates and a value at each, here the element's size; independent of the model's own mesh, which is
// cleared) behind a PostView field. Where the view has no element (a curved face beyond the old mesh's chords), gmsh
// takes the largest size, so Mesh.MeshSizeMax holds. Returns the view's and the field's tags, for removal.
std::pair<int, int> add_background_sizes(const MeshSizeField& field, double metres_to_gmsh) {
  const Eigen::Index elements = field.mesh.element_count();
  std::vector<double> data;
  data.reserve(static_cast<std::size_t>(16 * elements));
  for (Eigen::Index e = 0; e < elements; ++e) {
    for (int axis = 0; axis < 3; ++axis)
      for (int a = 0; a < 4; ++a) data.push_back(field.mesh.nodes(field.mesh.tets(e, a), axis) * metres_to_gmsh);
    for (int a = 0; a < 4; ++a) data.push_back(field.sizes(e) * metres_to_gmsh);
  }
  const int view = gmsh::view::add("fbprep sizes");
  gmsh::view::addListData(view, "SS", static_cast<int>(elements), data);
  const int tag = gmsh::model::mesh::field::add("PostView");
  gmsh::model::mesh::field::setNumber(tag, "ViewTag", view);
  gmsh::model::mesh::field::setAsBackgroundMesh(tag);
  return {view, tag};
}

// The model meshed at element size `size` (gmsh's coordinates), its tetrahedra of the order asked read, quadratic ones
// through gmsh's smoothing (optimize_folded; `repair` says what it did).
GmshTetrahedra mesh_at(const std::string& name, double size, const GmshImportOptions& options,
                       std::optional<CurvedElementRepair>& repair, double metres_to_gmsh) {
  gmsh::model::mesh::clear();
  gmsh::option::setNumber("Mesh.MeshSizeMax", size);
  if (options.thin_feature_elements > 0.0) detail::gmsh_call(name, [&] { size_thin_features(size, options.thin_feature_elements); });
  std::optional<std::pair<int, int>> background;
  if (options.size_field)
    detail::gmsh_call(name, [&] { background = add_background_sizes(*options.size_field, metres_to_gmsh); });
  detail::gmsh_call(name + ": meshing failed", [&] {
    detail::SilencedStdStreams quiet;
    gmsh::model::mesh::generate(3);
    if (options.order == 2) {  // mid-edge nodes of boundary edges placed on the CAD surfaces (curved elements)
      gmsh::option::setNumber("Mesh.SecondOrderLinear", 0);
      gmsh::model::mesh::setOrder(2);
    }
  });
  if (background)
    detail::gmsh_call(name, [&] {
      gmsh::model::mesh::field::remove(background->second);
      gmsh::view::remove(background->first);
    });
  GmshTetrahedra tetrahedra = tetrahedra_from_gmsh(name, options.order.value_or(kDefaultElementOrder));
  repair.reset();
  if (tetrahedra.quadratic) repair = optimize_folded(name, tetrahedra, options);
  return tetrahedra;
}

// The volume of the mesh (gmsh's coordinates): the quadratic elements' by the 4-point rule (mesh_quality), or nullopt
// when the mesh falls apart into several pieces (an assembly, refused later: no point in refining it).
std::optional<double> resolved_volume(const GmshTetrahedra& tetrahedra) {
  if (connected_components(tetrahedra.mesh).count != 1) return std::nullopt;
  return tetrahedra.quadratic ? mesh_quality(*tetrahedra.quadratic).volume_m3 : mesh_quality(tetrahedra.mesh).volume_m3;
}

}  // namespace

// Meshes the model, checked against the CAD solids' volume `solid` (gmsh's coordinates; nullopt: no CAD volume, no
// check). The mesh must hold it to options.volume_tolerance: a mesh coarser than the part's features drops them
// (a solid of gmsh's as1-tu-203 demo at the default size held 64 % of its volume, and the body file lost
// 36 % of the mass without a word), and linear elements cut curved faces along their chords. The default size is
// halved until the mesh holds the volume (at most kVolumeRefinements times); a size the user gave is kept, and a
// mesh that misses the volume is refused with a size that would do.
GmshTetrahedra mesh_resolving_the_volume(const std::string& name, double size, std::optional<double> solid,
                                         const UnitDecision& unit, const GmshImportOptions& options,
                                         ImportedMesh& result, double estimated) {
  const bool by_default = !(options.mesh_size > 0.0);
  auto progress = [&](double at) {
    if (options.progress)
      options.progress(fmt::format("meshing {} volume(s), element size {:.4g} m ({})", result.volumes,
                                   at * unit.gmsh_to_metres, to_string(options.algorithm)));
  };
  progress(size);
  GmshTetrahedra tetrahedra = mesh_at(name, size, options, result.curved_repair, 1.0 / unit.gmsh_to_metres);
  if (!solid) return tetrahedra;
  std::optional<double> volume = resolved_volume(tetrahedra);
  if (!volume) return tetrahedra;
  const double tolerance = options.volume_tolerance;
  auto error = [&](double v) { return v / *solid - 1.0; };
  const double first_error = error(*volume);
  result.first_volume_error = first_error;
  if (std::abs(first_error) <= tolerance) return tetrahedra;
  // Halve the size until the volume is held: the default's refinement, or the size to advise.
  // `trial` and `trial_error` are always the last size meshed and its error (review: the element limit broke the loop
  // after halving, and the refusal then named a size never meshed with the error of twice it).
  double trial = size, trial_error = first_error;
  GmshTetrahedra finer;
  std::optional<CurvedElementRepair> finer_repair;
  bool found = false, limited = false;
  for (int k = 1; k <= kVolumeRefinements && !found; ++k) {
    if (estimated * 8.0 > options.volume_search_elements) {
      limited = true;
      break;
    }
    estimated *= 8.0;
    const double next = 0.5 * trial;
    if (options.progress)
      options.progress(fmt::format("the mesh holds {:.2f} % of the CAD solid's volume (tolerance {:.2g} %): {}",
                                   100.0 * (1.0 + trial_error), 100.0 * tolerance,
                                   by_default ? "refining the default size" : "looking for a size that holds it"));
    progress(next);
    finer = mesh_at(name, next, options, finer_repair, 1.0 / unit.gmsh_to_metres);
    const std::optional<double> v = resolved_volume(finer);
    if (!v) break;  // the finer mesh fell apart: refused as disconnected below
    trial = next;
    trial_error = error(*v);
    found = std::abs(trial_error) <= tolerance;
  }
  const double given = by_default ? size * unit.gmsh_to_metres / metres_per(unit.geometry_unit) : options.mesh_size;
  const std::string unit_name(to_string(unit.geometry_unit));
  if (by_default && found) {
    result.mesh_size_m = trial * unit.gmsh_to_metres;
    result.refined_from_m = size * unit.gmsh_to_metres;
    result.curved_repair = std::move(finer_repair);
    return finer;
  }
  const std::string size_text =
      by_default ? fmt::format("the default element size ({:.4g} {})", given, unit_name)
                 : fmt::format("--mesh-size {:.4g} {}", given, unit_name);
  const double trial_given = trial * unit.gmsh_to_metres / metres_per(unit.geometry_unit);
  const double accepting = 1.05 * std::abs(first_error);  // a --volume-tolerance that takes this mesh (below 1)
  const std::string or_accept =
      accepting < 1.0 ? fmt::format(" (or --volume-tolerance {:.2g} accepts this mesh)", accepting) : std::string();
  if (trial == size)  // nothing finer was meshed: the element limit, or the finer mesh fell apart
    throw std::runtime_error(fmt::format(
        "{}: the mesh at {} holds {:.2f} % of the CAD solid's volume ({:.4g} m^3), beyond the {:.2g} % tolerance; {}{}",
        name, size_text, 100.0 * (1.0 + first_error), *solid * std::pow(unit.gmsh_to_metres, 3), 100.0 * tolerance,
        limited ? fmt::format("a finer mesh would pass {:.0e} tetrahedra, so none was tried: --order 2 follows curved "
                              "faces", options.volume_search_elements)
                : std::string("a finer mesh falls apart: the CAD solid may be open or self-intersecting"),
        or_accept));
  throw std::runtime_error(fmt::format(
      "{}: the mesh at {} holds {:.2f} % of the CAD solid's volume ({:.4g} m^3), beyond the {:.2g} % tolerance; {}", name,
      size_text, 100.0 * (1.0 + first_error), *solid * std::pow(unit.gmsh_to_metres, 3), 100.0 * tolerance,
      found ? fmt::format("--mesh-size {:.4g} {} holds it to {:.2f} %{}", trial_given, unit_name, 100.0 * trial_error,
                          or_accept)
            : std::abs(trial_error) < 0.5 * std::abs(first_error)
                  ? fmt::format("no size down to {:.4g} {} does (it holds {:.2f} % there; the error shrinks with the "
                                "size): --order 2 follows curved faces, or give a smaller --mesh-size", trial_given,
                                unit_name, 100.0 * (1.0 + trial_error))
                  : fmt::format("no size down to {:.4g} {} does (it holds {:.2f} %): the CAD solid may be open or "
                                "self-intersecting", trial_given, unit_name, 100.0 * (1.0 + trial_error))));
}

}  // namespace flexbody::preprocess::detail
