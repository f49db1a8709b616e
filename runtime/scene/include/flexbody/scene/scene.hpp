#pragma once
// flexbody/scene/scene.hpp: fbsim's scene file (YAML): bodies from body files, joints, forces, gravity, integrator settings and
// outputs, read into a runtime System. Every error is one "<scene>:<line>: <problem>" line.

#include "flexbody/format/yaml_reader.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/initial_assembly.hpp"
#include "flexbody/runtime/scene_builder.hpp"
#include "flexbody/runtime/system.hpp"
#include "flexbody/scene/output_budget.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <limits>
#include <string>
#include <vector>

namespace flexbody::scene {

/// One output file: a marker's position, velocity or orientation, a joint's reaction force and moment, a body's modal
/// coordinates, or an output region's elastic displacements and stresses.
struct Sensor {
  enum class Kind { marker, joint, modal, region };
  std::string name;
  Kind kind = Kind::marker;
  runtime::Marker marker;          ///< Kind::marker
  std::size_t joint = 0;           ///< Kind::joint: index into System::joints()
  int body = 0;                    ///< Kind::modal and Kind::region (and the marker's body)
  std::size_t region = 0;          ///< Kind::region: index into the body model's recovery regions
  /// marker: position, velocity, orientation; joint: reaction_force, reaction_moment; modal: modal_coordinates;
  /// region: displacement, stress
  std::vector<std::string> quantities;
};

/// A ParaView series of one body's deformed surface (runtime/paraview_series.hpp).
struct SurfaceSeries {
  int body = 0;
  bool stresses = true;
};

/// Which conservation laws a scene's motion must obey, so that a run can check them (simulation.cpp). The energy is
/// conserved when only gravity, undamped springs and joints that are not driven act (no damping, no applied force or
/// torque: a constant point force is conservative too, but its potential is not in System::energies); the angular
/// momentum about the centre of mass besides when nothing ties a body to ground (no joint or spring to ground, no
/// applied force or torque; uniform gravity exerts no moment about the centre of mass).
struct Conservation {
  bool energy = false;
  bool angular_momentum = false;
};

struct Scene {
  runtime::System system;
  runtime::GeneralizedAlphaOptions integrator;
  double end_time = 0.0;
  int output_every = 1;        ///< write every n-th step
  /// Write at the first step at or after each multiple of this time [s] instead (integrator output_interval): a
  /// change of step then leaves the rows' times as they are.
  std::optional<double> output_interval;
  bool monitors = false;       ///< monitors.csv: energies, ‖AᵀA − I‖, constraint residuals, Newton iterations
  std::vector<Sensor> sensors;
  std::vector<SurfaceSeries> paraview;  ///< DIR/<body>.pvd + DIR/<body>/*.vtu
  int paraview_every = 1;               ///< a frame every n-th step
  std::optional<double> paraview_interval;  ///< a frame at each multiple of this time [s] instead (paraview interval)
  Conservation conserves;
  OutputBudget budget;  ///< what a run to end_time may write into its directory (output_budget.hpp)
  /// Where the scene sets the step, the CSV outputs' and the ParaView series' frequency ("scene.yaml:7"), for the
  /// budget's refusal.
  std::string step_at = "the scene", outputs_at = "the scene", paraview_at = "the scene";
  /// checkpoint: {interval: SECONDS}: a run with an output directory writes DIR/checkpoint.h5 every `interval` seconds
  /// of wall-clock time (Simulation); nullopt: none but those fbsim writes when it is stopped.
  std::optional<double> checkpoint_interval;
  /// What the scene was read from, for a checkpoint's identity: the SHA-256 of the scene file's bytes (of the
  /// document's YAML for a scene built in code), and every body file it read, in the order of `bodies`, with the
  /// SHA-256 its seal records, read as the scene is read (so that a file replaced during the run does not become the
  /// run's; a file replaced while the scene is being read is not caught).
  std::string source_sha256;
  std::vector<std::filesystem::path> body_files;
  std::vector<std::string> body_sha256;
  runtime::InitialAssemblyReport assembly;          ///< how the initial assembly moved the bodies
  std::vector<runtime::RemovedConstraint> removed;  ///< joint rows left out as redundant (System::remove_redundant_constraints)
};

/// The most steps a scene may take: a step many orders too small (1e-20 s for 1e-4 s) would otherwise run for
/// centuries, or (below about 1e-19 of the end time) not at all. 1e9 steps of a 20-mode body take about 6 hours.
inline constexpr double kMostSteps = 1e9;

/// The steps from 0 to `end` with step `h`: whole steps, and the last one shortened to end exactly on `end` when
/// `end` is not a whole number of steps (a remainder below GeneralizedAlpha::kStepToSlack h is rounding, not a step).
/// The rounding of end / h itself grows with the count (8 ε per step count), so that counts past 1e7 do not gain a
/// spurious last step of a few ε end.
[[nodiscard]] inline double step_count(double end, double h) {
  const double steps = end / h;
  const double slack = std::max(runtime::GeneralizedAlpha::kStepToSlack, 8.0 * std::numeric_limits<double>::epsilon() * steps);
  return std::max(1.0, std::ceil(steps - slack));
}

/// step: auto's defaults: CSV rows (and ParaView frames) at end / kAutoRows (kAutoFrames) apart, steps of at most
/// end / kAutoLongestSteps, the first step min(max_step, output_interval) / kAutoFirstStepDivisor (the controller
/// grows it by up to 2 per step, so a first step too small costs about log2 of it in steps), and the floor, min_step,
/// the first step / kDefaultSplits.
inline constexpr double kAutoRows = 500.0, kAutoFrames = 100.0, kAutoLongestSteps = 10.0, kAutoFirstStepDivisor = 100.0;

/// What fbsim's command line changes in a scene (nullopt: the scene's own).
struct SceneOverrides {
  std::optional<double> end_time;  ///< --end [s]: the integrator's end time, checked as the scene's `end` is
  std::optional<double> max_output;  ///< --max-output [bytes]: the output budget's size, over the scene's
};

/// What a scene needs once its bodies, joints, forces and springs are in: the joint rows that repeat others left
/// out (Scene::removed, System::remove_redundant_constraints), the conservation laws its motion must obey
/// (Scene::conserves), and the initial assembly (Scene::assembly, runtime::initial_assembly). Throws
/// runtime::InitialAssemblyError naming the joint whose gap is too large, std::invalid_argument for a degenerate body.
void finish_scene(Scene& scene, const runtime::InitialAssemblyOptions& assembly = {});

/// Reads and assembles a scene; body files are read relative to the scene's directory.
[[nodiscard]] Scene read_scene(const std::filesystem::path& file, const SceneOverrides& overrides = {});

/// What a scene's document cannot say, added by its builder once the document's bodies, joints, forces and springs
/// are in and before the scene is finished (the Python package's forces that are functions of Python).
using SceneExtras = std::function<void(runtime::SceneBuilder& builder)>;

/// Reads and assembles a scene from its document `root` (a scene file's, or one built in code, whose nodes carry no
/// lines): errors begin with `source`, body files are read relative to `base`.
[[nodiscard]] Scene read_scene(const YAML::Node& root, const std::string& source, const std::filesystem::path& base,
                               const SceneOverrides& overrides = {}, const SceneExtras& extras = {});

}  // namespace flexbody::scene
