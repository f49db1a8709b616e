#pragma once
// flexbody/preprocess/gmsh_import.hpp: CAD or mesh file -> tetrahedral mesh (linear or quadratic) in metres (gmsh).

#include "flexbody/preprocess/cad_surface.hpp"
#include "flexbody/preprocess/curved_mesh_repair.hpp"
#include "flexbody/preprocess/length_unit.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <array>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace flexbody::preprocess {

enum class InputFormat { step, iges, brep, geo, msh };
[[nodiscard]] std::string_view to_string(InputFormat format);
/// From the file extension (case-insensitive); throws std::invalid_argument for anything else.
[[nodiscard]] InputFormat input_format_of(const std::filesystem::path& path);

/// gmsh's 3D meshing algorithm: its default Delaunay (single-threaded, reproducible) or HXT (Mesh.Algorithm3D = 10:
/// faster, on OpenMP's threads, but its mesh differs from run to run).
enum class MeshAlgorithm { delaunay, hxt };
[[nodiscard]] std::string_view to_string(MeshAlgorithm algorithm);  ///< "delaunay", "hxt"
/// From "delaunay" or "hxt"; nullopt for anything else.
[[nodiscard]] std::optional<MeshAlgorithm> mesh_algorithm_from_string(std::string_view text);

/// The element order of a mesh fbprep makes when none is asked for: quadratic tetrahedra. Measured on 44 public CAD
/// parts at the default size (bench/README.md, "cad_corpus_bench"): linear tetrahedra put the first frequency 0.4 to
/// 375 % above the quadratic one (more than 5 % on 30 parts), and reaching 5 % with them costs several halvings of the
/// size; quadratic ones are within 3 % by the error estimate on all but one, at a median of 4 s instead of 1 s.
inline constexpr int kDefaultElementOrder = 2;

/// GmshImportOptions::thin_feature_elements sizes no point below this fraction of the mesh size: without it a CAD
/// curve of a micrometre (a chamfer's edge) asks for micrometre elements (0603_SMD.stp was still meshing at 5 GB
/// after two minutes).
inline constexpr double kThinFeatureFloor = 0.25;

/// Element sizes over an earlier mesh of the same part (mesh_refinement.hpp): inside tetrahedron e of `mesh` (corner
/// nodes, metres, the input's frame) gmsh is asked for elements of `sizes(e)` metres at most.
struct MeshSizeField {
  TetMesh mesh;
  Eigen::VectorXd sizes;
};

struct GmshImportOptions {
  /// Length unit of the input's coordinates, as the user gives it. It wins over what a STEP file
  /// declares (a file written with a wrong declared unit is common: gmsh's writer always declares mm);
  /// without it a STEP file's declared unit holds. BREP, .geo and .msh files carry no unit: `unit` is
  /// required for them. An IGES file's unit, or a STEP unit other than mm, cm, m, inch, is converted by
  /// OpenCASCADE with a factor fbprep does not know, so `unit` is refused for them. Every length in
  /// these options (and in a body spec) is in the unit the geometry is read in: ImportedMesh::unit.
  std::optional<LengthUnit> unit;
  /// How `unit` was given, for the report, e.g. "the body spec's unit: m" (empty: "--unit <unit>").
  std::string unit_source;
  /// Target element size in the unit the geometry is read in (0: one twenty-fifth of the
  /// bounding-box diagonal).
  double mesh_size = 0.0;
  /// Element order: 1 (linear tetrahedra) or 2 (quadratic, ImportedMesh::quadratic). Unset: kDefaultElementOrder for
  /// geometry that fbprep meshes, and for a .msh the order of the tetrahedra it holds (both kinds: refused unless set).
  std::optional<int> order;
  /// How far the mesh's volume may be from the CAD solid's, relative to it (dimensionless): the default element size is
  /// halved until the mesh holds it, a size the user gave is refused if it does not (with a size that would do).
  double volume_tolerance = 5e-3;
  /// The search for a size that holds the volume meshes no size whose estimated tetrahedra exceed this count (its
  /// cost must stay below a run's: 2e6 tetrahedra are about 1e6 linear DOFs); past it, the refusal says so.
  double volume_search_elements = 2e6;
  /// Thin features meshed with about this many elements across (0: off, the default): each CAD point's element size
  /// is the shortest CAD curve through it over this count, clamped to [kThinFeatureFloor, 1] × the mesh size, and
  /// gmsh spreads the point sizes over the faces and the volume. A part's thin leads, ribs and walls are bounded by
  /// short curves, so they refine where the uniform size would put one element through them; so do small chamfers,
  /// which are no thin features (a chip resistor: 18 times the DOFs for 0.01 % of its first frequency), which is why
  /// fbprep's default is the refinement by the error estimate instead (fbprep_pipeline.hpp, error_target). Refused for
  /// a .msh.
  double thin_feature_elements = 0.0;
  /// Sizes from an earlier mesh (fbprep's refinement by the error estimate), on top of mesh_size; null: none. Refused
  /// for a .msh.
  std::shared_ptr<const MeshSizeField> size_field;
  /// The 3D algorithm (ignored for a .msh, whose tetrahedra are used as they are).
  MeshAlgorithm algorithm = MeshAlgorithm::delaunay;
  /// Called with a short message before each long step.
  std::function<void(const std::string&)> progress;
  /// Called with a warning the user must see before the work goes on (a part's implausible size).
  std::function<void(const std::string&)> warning;
};

/// What the import did about quadratic tetrahedra folded by their curved edges (curved_mesh_repair.hpp): gmsh's
/// elastic smoothing of the high-order nodes, then straightening of what it left.
struct CurvedElementRepair {
  Eigen::Index elements = 0;        ///< quadratic tetrahedra in the mesh
  Eigen::Index folded = 0;          ///< folded when gmsh raised the order
  Eigen::Index after_elastic = -1;  ///< folded after gmsh's elastic smoothing ("HighOrderElastic"; -1: not needed)
  std::string elastic_message;      ///< gmsh's error, if the smoothing failed (its mesh is used as it was left)
  Straightening straightened;       ///< what the smoothing left, straightened
  double seconds = 0.0;             ///< wall time of all of it
  /// Folded elements the smoothing left (to be straightened).
  [[nodiscard]] Eigen::Index left() const { return after_elastic >= 0 ? after_elastic : folded; }
};

struct ImportedMesh {
  TetMesh mesh;  ///< nodes in metres, in the input's frame; with order 2 the quadratic mesh's corners
  /// With order 2: the 10-node tetrahedra, their mid-edge nodes on the CAD surfaces where the edge lies on one
  /// (curved elements), nodes numbered as `mesh`'s first, each element's Jacobian checked positive.
  std::optional<Tet10Mesh> quadratic;
  /// With order 2 and a mesh made here: what was done about folded elements (nothing when `folded` is 0).
  std::optional<CurvedElementRepair> curved_repair;
  InputFormat format = InputFormat::step;
  LengthUnit unit = LengthUnit::metre;  ///< the unit the geometry was read in (and every input length)
  std::string unit_reason;              ///< why that unit (for the report)
  /// The unit the file declares, when fbprep reads one (STEP: mm, cm, m, inch); nullopt otherwise.
  std::optional<LengthUnit> declared_unit;
  /// True when the user's unit differs from the declared one and replaced it.
  bool unit_overrides_declared = false;
  int volumes = 0;                      ///< CAD volumes (0 for .msh)
  /// When the input had faces and no volume: how many faces were sewn into its solid(s) (0: not sewn).
  int sewn_faces = 0;
  /// Points, curves and faces of a CAD file that lie beside its solids, bounding none: not meshed, and reported.
  std::array<int, 3> loose_entities{0, 0, 0};
  double mesh_size_m = 0.0;             ///< element size asked of gmsh [m] (0 for .msh)
  /// The CAD solids' volume [m³] (OpenCASCADE's mass properties), against which the mesh's volume is checked; nullopt
  /// for a .msh, or a .geo in gmsh's built-in kernel.
  std::optional<double> cad_volume_m3;
  /// The CAD model's bounding-box diagonal [m] (0 for .msh), and a warning when it is implausible for a machine part
  /// (under 0.1 mm or over 1 km: nearly always a unit mistake), empty otherwise.
  double extent_m = 0.0;
  std::string size_warning;
  /// The first mesh's volume / the CAD volume − 1, before any refinement (nullopt: no CAD volume, or not checked).
  std::optional<double> first_volume_error;
  /// When the default size was refined to hold the volume: the size it started from [m] (0: not refined).
  double refined_from_m = 0.0;
  bool meshed_here = true;              ///< false when a .msh's tetrahedra were used as they are
  /// The CAD surfaces that carry boundary triangles of the mesh, by tag (a .msh lists those it stores).
  std::vector<CadSurface> surfaces;
};

/// Imports `path` with gmsh and returns its tetrahedra in metres. Throws std::runtime_error
/// with one line naming the file and the problem: unreadable file, no volume, several disconnected
/// solids, inverted or zero-volume elements, a .msh without tetrahedra, no unit for a BREP, .geo or
/// .msh; std::invalid_argument for a unit that cannot be applied (IGES, a STEP unit fbprep cannot read).
[[nodiscard]] ImportedMesh import_tet_mesh(const std::filesystem::path& path, const GmshImportOptions& options);

}  // namespace flexbody::preprocess
