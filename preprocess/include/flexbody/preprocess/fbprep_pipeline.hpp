#pragma once
// flexbody/preprocess/fbprep_pipeline.hpp: the whole of fbprep as one call, and its summary.
//
// \code
//   flexbody::preprocess::PrepOptions options;
//   options.input = "bracket.step";
//   options.output = "bracket.fbh5";
//   options.modes.modes = 12;
//   const auto summary = flexbody::preprocess::run_fbprep(options);
//   std::cout << summary.full_report();
// \endcode

#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/interfaces.hpp"
#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/mesh_topology.hpp"
#include "flexbody/preprocess/static_correction.hpp"

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace flexbody::preprocess {

/// The fbprep version written into every body file (created_by): the package version of CMakeLists.txt.
extern const char* const kFbprepVersion;

/// An output region for stress recovery: the nodes of the selected surface patch, every node, or every boundary node.
struct OutputRegionRequest {
  std::string name;
  std::optional<Selector> select;  ///< input frame, the input's length unit; nullopt: the whole body or its surface
  bool surface = false;            ///< without a selector: the boundary's nodes (a spec's `select: surface`)
};

/// Without output regions in the request, the whole body is one ("body") if its stress modes take at
/// most this many bytes (6 n_n x 3 n_f doubles); else its boundary nodes ("surface", what ParaView pictures draw) if
/// theirs do; and there are none otherwise.
inline constexpr double kDefaultRecoveryBytes = 64e6;

/// How the reduction basis is made.
enum class ReductionKind { free_free, craig_bampton };
[[nodiscard]] std::string_view to_string(ReductionKind kind);  ///< "free-free", "craig-bampton"

/// PrepOptions::error_target's default: the level at which fbprep warns (kAccuracyWarning).
inline constexpr double kDefaultErrorTarget = 0.05;
/// The refined mesh has at most this many times the first one's tetrahedra (and at most
/// GmshImportOptions::volume_search_elements): its modes cost about this much more than the first mesh's.
inline constexpr double kRefinementGrowth = 8.0;

struct PrepOptions {
  std::filesystem::path input;
  /// The body file to write. It may not be the input or the spec (the same file by any path), and an existing
  /// file there is replaced only if it is empty or begins like a body file (format::begins_like_body_file).
  std::filesystem::path output;
  std::filesystem::path spec;  ///< the body spec the options were read from (read_body_spec); empty: none
  GmshImportOptions mesh;  ///< unit, mesh size, order
  Material material = parse_material("steel");
  FreeFreeOptions modes;   ///< number of modes (Craig-Bampton: fixed-interface modes), fmax, eigensolver
  ReductionKind reduction = ReductionKind::free_free;
  /// Interfaces to build as markers (input frame, lengths in the input's unit, like mesh.mesh_size).
  /// With free-free modes only rbe3 couplings: an rbe2 tie changes the modes and needs a Craig-Bampton
  /// reduction.
  std::vector<InterfaceRequest> interfaces;
  /// Load points: rbe3 interfaces that also add their static correction modes to the basis.
  std::vector<LoadPointRequest> load_points;
  /// Output regions for stress recovery; nullopt: the default (kDefaultRecoveryBytes), empty: none.
  std::optional<std::vector<OutputRegionRequest>> output_regions;
  /// The geometric stiffness of the prestress cases (geometric_stiffness.hpp: the six centrifugal ones and a unit
  /// force and moment at each interface), projected on the GCMS fields, for rotating and preloaded parts.
  bool geometric_stiffness = false;
  /// The relative error of the first frequency (dimensionless, f_h / f − 1 by the error estimate) above which the
  /// default mesh is refined once where the estimate puts the error (mesh_refinement.hpp), aiming at half of it with
  /// at most kRefinementGrowth times the tetrahedra; 0: never. Only a mesh fbprep sizes itself is refined: not with
  /// mesh.mesh_size or mesh.thin_feature_elements given, not a .msh, and free-free modes only (they carry the
  /// estimate).
  double error_target = kDefaultErrorTarget;
  /// The options as the user gave them, recorded in the body file's provenance.
  std::vector<std::pair<std::string, std::string>> recorded_options;
  /// Called with a short message at the start of each long step.
  std::function<void(const std::string&)> progress;
};

/// Wall time and the process' memory high-water mark at the end of one stage.
struct StageRecord {
  std::string name;
  double seconds = 0.0;
  double peak_memory_mb = 0.0;
};

/// The estimated frequency error (relative) above which fbprep warns.
inline constexpr double kAccuracyWarning = 0.05;

/// What fbprep did, for FullReport() and --json. Starts empty; run_fbprep fills every field.
struct PrepSummary {
  std::filesystem::path input, output;
  std::string input_sha256;
  InputFormat format = InputFormat::step;
  std::string unit, unit_reason;  ///< the unit the input was read in (every input length is in it), and why
  std::string declared_unit;      ///< the unit the input declares, if fbprep reads one ("" otherwise)
  bool unit_overrides_declared = false;  ///< the user's unit replaced a different declared one
  int volumes = 0;
  int sewn_faces = 0;  ///< the input had faces and no volume: this many were sewn into its solid (0: not sewn)
  std::array<int, 3> loose_entities{0, 0, 0};  ///< points, curves, faces beside the solids, left out (gmsh_import.hpp)
  bool meshed_here = true;
  double mesh_size_m = 0.0;
  MeshAlgorithm mesher = MeshAlgorithm::delaunay;  ///< gmsh's 3D algorithm (when meshed_here)
  int element_order = 1;  ///< 1: linear tetrahedra, 2: quadratic (10 nodes; nodes and DOFs count the mid-edge nodes)
  /// The CAD solids' volume [m³], when the input is a CAD model (gmsh_import.hpp); the mesh's is quality.volume_m3.
  std::optional<double> cad_volume_m3;
  double extent_m = 0.0;      ///< the CAD model's bounding-box diagonal [m] (0 for .msh)
  std::string size_warning;  ///< set when extent_m is implausible for its unit (gmsh_import.hpp)
  /// The default element size was refined from this one [m] (0: not), whose mesh was off the CAD volume by
  /// first_volume_error (relative).
  double refined_from_m = 0.0;
  std::optional<double> first_volume_error;
  /// quality.volume_m3 / cad_volume_m3 − 1 (0 without a CAD volume).
  [[nodiscard]] double volume_error() const { return cad_volume_m3 ? quality.volume_m3 / *cad_volume_m3 - 1.0 : 0.0; }
  /// Element order 2, meshed here: folded elements and what cured them (gmsh_import.hpp).
  std::optional<CurvedElementRepair> curved_repair;
  /// Surface triangles: with element order 2, four per 6-node boundary face (formats/SCHEMA.md, Mesh).
  Eigen::Index nodes = 0, elements = 0, dofs = 0, surface_triangles = 0;
  MeshQuality quality;
  Material material;
  format::MassProperties mass;
  ReductionKind reduction = ReductionKind::free_free;
  Eigen::VectorXd frequencies_hz, relative_residuals;
  /// Free-free: each eigenmode's estimated discretisation error f_h / f − 1 (error_estimate.hpp;
  /// empty otherwise).
  Eigen::VectorXd frequency_errors;
  /// When the default mesh was refined by the error estimate (PrepOptions::error_target): the first mesh's numbers and
  /// the plan (mesh_refinement.hpp). Every other field describes the refined mesh.
  struct MeshRefinement {
    double error_target = 0.0;        ///< PrepOptions::error_target
    double first_frequency_hz = 0.0;  ///< the first mesh's first elastic frequency
    double first_estimate = 0.0;      ///< and its estimated relative error
    Eigen::Index first_dofs = 0, first_elements = 0;
    double predicted_elements = 0.0;  ///< the plan's tetrahedra
    double predicted_share = 0.0;     ///< the plan's estimated relative eigenvalue error left (all modes' shares)
    bool budget_bound = false;        ///< kRefinementGrowth, not the target, set the sizes
    double first_seconds = 0.0;       ///< the first mesh's pass, from the import to the estimate
  };
  std::optional<MeshRefinement> refinement;
  /// "the first frequency is likely N % too high ..." when the estimate passes kAccuracyWarning, else empty.
  [[nodiscard]] std::string accuracy_warning() const;
  /// Free-free only: each mode's rounding floor of its residual (eigen_residual.hpp).
  Eigen::VectorXd residual_floors;
  /// Craig-Bampton only: the clamped problem's frequencies, residuals and their rounding floors.
  Eigen::VectorXd fixed_interface_frequencies_hz, fixed_interface_residuals, fixed_interface_residual_floors;
  double shift = 0.0;
  std::string eigensolver;
  double rigid_body_residual = 0.0, rigid_body_coupling = 0.0;
  int solver_runs = 0, restarts = 0, operator_applies = 0;
  ShiftSolveStats factor;
  /// GCMS fields kept and dropped (formulations.md, "The Method": dependent fields), and the condition numbers of
  /// Ῡᵀ M_s Ῡ and of G before and of G after (+inf: singular to working precision): Jacobi-scaled
  /// (D^-1/2 G D^-1/2, D = diag G: unit-free, the same for the same shape at every size) and in SI units
  /// (which change with the part's size).
  Eigen::Index gcms_fields = 0, dropped_fields = 0;
  double condition_mode_gram_before = 0.0, condition_mass_before = 0.0, condition_mass_after = 0.0;
  double condition_mass_scaled_before = 0.0, condition_mass_scaled_after = 0.0;
  /// The interfaces built: name, coupling, node count, reference point in the input frame.
  struct InterfaceLine {
    std::string name, coupling;
    Eigen::Index nodes = 0;
    Eigen::Vector3d reference_point_input = Eigen::Vector3d::Zero();
  };
  std::vector<InterfaceLine> interfaces;
  /// Static correction: the unit loads ("hook:fx", ...), the solves, and how many modes are static
  /// corrections (free-free: the last ones; Craig-Bampton: 0, they are folded into its basis).
  std::vector<std::string> static_loads;
  StaticCorrectionStats static_correction;
  /// The geometric stiffness's load cases (empty: not asked for) and their static solves.
  std::vector<std::string> prestress_cases;
  StaticCorrectionStats prestress;
  Eigen::Index static_correction_modes = 0;
  /// Output regions for stress recovery (name, nodes) and why these (the default rule or the spec).
  struct RegionLine {
    std::string name;
    Eigen::Index nodes = 0;
  };
  std::vector<RegionLine> output_regions;
  std::string output_regions_reason;
  std::vector<StageRecord> stages;
  double total_seconds = 0.0;
  double peak_memory_mb = 0.0;
  std::uintmax_t output_bytes = 0;

  /// The largest relative residual / rounding floor of the eigenmodes fbprep checks: the free-free normal modes,
  /// or the Craig-Bampton fixed-interface modes (each is at most kResidualFloorFactor, or below 1e-8).
  [[nodiscard]] double max_residual_to_floor() const;
  [[nodiscard]] std::string full_report() const;
  /// The summary as one JSON object (a single line).
  [[nodiscard]] std::string json() const;
};

/// Runs every stage and writes options.output atomically. Throws with one line naming the problem, and
/// then leaves no file under options.output: std::invalid_argument when the options ask for something
/// impossible (a bad value, more modes than the mesh has, an output that is the input, ...),
/// std::runtime_error when the input cannot be read or a computation fails.
[[nodiscard]] PrepSummary run_fbprep(const PrepOptions& options);

/// The process' memory high-water mark (VmHWM) in MB.
[[nodiscard]] double peak_memory_mb();

}  // namespace flexbody::preprocess
