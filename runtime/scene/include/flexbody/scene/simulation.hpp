#pragma once
// flexbody/scene/simulation.hpp: a scene's run: the integrator, the checks of a run (energy and angular momentum of
// conservative scenes, constraint residuals, the model's validity), and the scene's outputs, written as fbsim
// writes them (one CSV per output, monitors.csv, ParaView series) and/or kept in memory as tables (the Python
// package's arrays). fbsim and the Python package run scenes through it.

#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/scene/scene.hpp"

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace flexbody::scene {

/// How a run ended: Simulation::run's or step()'s last call.
enum class Termination {
  running,      ///< no run() has ended yet: the start, step() calls, a resumed run, or a state set since
  end_reached,  ///< run() reached its end time
  /// run()'s `stop` asked it to stop (fbsim: a signal), or its `progress` threw RunInterrupted (Python: Ctrl-C)
  stopped,
  step_failed,  ///< a step failed (runtime::StepFailure; RunSummary::termination_message says why)
  error,        ///< an exception from the scene's own functions (a force's) ended it
};

/// "running", "end reached", "stopped", "step failed", "error": how fbsim and summary_json name a Termination.
[[nodiscard]] const char* termination_name(Termination termination);

struct RunSummary {
  /// How the run ended, the time of its last completed step [s], and for a failed step or an error the reason (the
  /// exception's message).
  Termination termination = Termination::running;
  double time = 0.0;
  std::string termination_message;
  long steps = 0;
  long newton_iterations = 0;
  long newton_matrices = 0;  ///< Newton matrices built (factorizations)
  /// Steps (or pieces of steps) whose Newton iteration failed and that were taken again in halves, and the smallest
  /// piece taken [s] (the integrator's step when none was halved).
  long retried_steps = 0;
  double smallest_step = 0.0;
  /// step: auto (error control): the steps taken again because their local error estimate was above
  /// error_tolerance, those accepted above it at min_step, and the largest step taken [s] (smallest_step: the smallest
  /// the controller chose; steps shortened to land on a row's time are not counted). With a fixed step: 0, 0, the step.
  long rejected_steps = 0, steps_above_tolerance = 0;
  double largest_step = 0.0;
  bool sparse = false;       ///< the reduced Newton matrix was factorized sparse (GeneralizedAlpha::sparse)
  double cpu_seconds = 0.0;
  double energy_initial = 0.0, energy_final = 0.0;
  /// max_t |E(t) − E_0| / max_t (kinetic + elastic + spring energy): meaningful for conservative scenes (no
  /// applied forces, torques or damping, whose work it does not count).
  double energy_drift = 0.0;
  double max_constraint_residual = 0.0;  ///< max over the checked steps (every kCheckEvery-th) of |Φ|∞
  double wall_seconds = 0.0;             ///< the steps: integration, checks and outputs
  double integrator_wall_seconds = 0.0;  ///< GeneralizedAlpha::step alone
  /// Conservative scenes (Scene::conserves), over the checked steps: the largest (E(t) − E_0) / (the largest kinetic +
  /// elastic + spring energy so far), and the largest (|L(t)| − |L_0|) / |L_0| of the angular momentum about the
  /// centre of mass; each denominator at least 1e-9 of the magnitudes of the terms summed (round-off); 0 when not
  /// checked.
  double energy_growth = 0.0, angular_momentum_growth = 0.0;
  /// One line per conservation law that a conservative scene broke by more than kConservationTolerance, and the
  /// integrator's lines about the model's validity (GeneralizedAlpha::warnings), in the order they arose.
  std::vector<std::string> warnings;
  std::size_t conservation_warnings = 0, validity_warnings = 0;  ///< how many of each
  std::vector<std::filesystem::path> files;
  /// With an output directory: what a run to the scene's end was estimated to write before it started, and what is
  /// on disk now (the files above and the ParaView frames) [bytes, files].
  double estimated_bytes = 0.0, estimated_files = 0.0;
  double written_bytes = 0.0, written_files = 0.0;
  /// A resumed run (Resume): the simulated time of the checkpoint it continued from [s]; the counts above are the
  /// whole run's, from t = 0.
  std::optional<double> resumed_at;
};

/// Energies, constraint residuals and momenta are evaluated every kCheckEvery steps and at the end of a run (an
/// evaluation costs about a fifth of a 16-mode step; the drift they watch is slow). Monitor rows evaluate their own.
/// The interval is odd because the instability of generalized-α near ρ∞ = 1 is an oscillation of period 2 h: an even
/// interval samples one phase only (measured: a spinning plate whose energy is 0.8 % high at every other step
/// showed no growth at every 10th).
inline constexpr long kCheckEvery = 9;
/// A conservative scene whose energy grows by more than this fraction of the largest kinetic + elastic + spring
/// energy, or whose angular momentum about the centre of mass grows by more than this fraction of its initial
/// magnitude, gets a warning (on stderr when it happens, in RunSummary::warnings and fbsim --json). Generalized-α
/// with ρ∞ < 1 only dissipates, and with ρ∞ = 1 its energy error oscillates at O((ω h)²), 1e-5 for the rigid
/// pendulum at ω h = 4e-3 (docs/accuracy-and-speed.md).
inline constexpr double kConservationTolerance = 1e-3;

/// One output's recorded rows (an output of the scene, or "monitors").
struct OutputTable {
  std::string name;
  std::vector<std::string> columns;  ///< "x [m]", ...: the CSV file's header after its time column
  std::vector<double> times;         ///< [s], one per row
  std::vector<double> values;        ///< row by row, columns.size() per row
};

/// Where a run's outputs go.
struct OutputSinks {
  /// One CSV file per output, monitors.csv and the ParaView series, in this directory (created).
  std::optional<std::filesystem::path> directory;
  bool in_memory = false;  ///< tables(): the outputs and monitors (no ParaView series)
};

/// The checkpoint a run with an output directory writes there (Simulation::checkpoint).
inline constexpr const char* kCheckpointFileName = "checkpoint.h5";

/// A run to continue: its checkpoint file (Simulation's resuming constructor).
struct Resume {
  std::filesystem::path checkpoint;
};

/// What a run()'s `progress` function throws to stop the run at once, at the last completed step (recorded, as after
/// a failed step), with the termination `stopped`: an interrupt that must reach the caller as an exception (Python's
/// KeyboardInterrupt). what() says what stopped it.
class RunInterrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A checkpoint that does not belong to the scene (another scene file or body file, another step), or that does not
/// match its output directory (a CSV file shorter than it was, a frame missing): one line naming what differs.
class CheckpointMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Simulation {
 public:
  /// Starts the run of `scene` at t = 0: builds the integrator (throws std::invalid_argument for a scene whose
  /// initial state or constraints are inconsistent, before any file is made), checks what a run to the scene's end
  /// would write against Scene::budget (throws OutputBudgetError, before any file is made), opens the sinks and
  /// records the initial state. `warn` gets each warning line when it arises (RunSummary::warnings keeps them all).
  Simulation(Scene scene, const OutputSinks& sinks, std::function<void(const std::string&)> warn = {});
  /// Continues the run of `scene` that wrote `from.checkpoint` (Simulation::checkpoint), into `sinks.directory`,
  /// where that run wrote: the steps that follow, and every output file, are what the run would have given had it
  /// never stopped, bit for bit. Each CSV file is cut back to its length at the checkpoint and continued; each
  /// ParaView series continues from its frames then. Refused with CheckpointMismatch (one line, naming what differs)
  /// for a checkpoint of another scene file, body file, step or ρ∞, or when the directory's files do not match it;
  /// format::BodyFileError for a damaged or foreign checkpoint file. Rows kept in memory start empty.
  Simulation(Scene scene, const OutputSinks& sinks, const Resume& from, std::function<void(const std::string&)> warn = {});
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  /// One step of the scene's step size. Rows are recorded every Scene::output_every steps (ParaView frames every
  /// Scene::paraview_every), counted from the start.
  void step();
  /// Steps to `end` [s]: whole steps, the last one shortened to end on `end` exactly (step_count); the state at
  /// `end` is recorded whatever output_every says. `progress` gets the time every 100 steps. Nothing to do when the
  /// time is `end` up to the rounding of t0 + k h; throws std::invalid_argument for an `end` before the current time
  /// or more than kMostSteps steps ahead. The CSV files are complete up to the
  /// last row when it returns (step() leaves them to the stream's buffer).
  /// `stop`, when given, is asked after each step: true ends the run there (after the step is recorded as output_every
  /// says), and run() returns false; it returns true when the run reached `end`.
  bool run(double end, const std::function<void(double)>& progress = {}, const std::function<bool()>& stop = {});
  // Either throws runtime::StepFailure for a step that fails, and passes an exception from the scene's own
  // functions (a force's) through; both leave the state at the last completed step, which is recorded first.

  [[nodiscard]] const Scene& scene() const;
  [[nodiscard]] const runtime::GeneralizedAlpha& integrator() const;
  [[nodiscard]] double time() const { return integrator().time(); }
  /// The integrator's state, and a restart from one (GeneralizedAlpha::set_state). After set_state the conservation
  /// checks and RunSummary's energies measure from the state set; the rows recorded so far stay, and the next ones
  /// follow from the state's time (earlier than the last row's when a run is set back).
  [[nodiscard]] runtime::IntegratorState state() const;
  void set_state(const runtime::IntegratorState& state);
  /// Writes the run's checkpoint, `directory`/kCheckpointFileName (OutputSinks::directory; std::logic_error
  /// without one), atomically: the integrator's state and history (GeneralizedAlpha::save), the counters and check
  /// baselines, each output file's length and each series' frames, and the identity of the scene and its body
  /// files. The scene's `checkpoint: {interval}` also writes it every so many seconds of wall-clock time.
  /// Returns its path.
  std::filesystem::path checkpoint();
  /// The simulated time of the last checkpoint written [s], if any.
  [[nodiscard]] std::optional<double> last_checkpoint() const;
  /// The run so far.
  [[nodiscard]] RunSummary summary() const;
  /// How the run ended (RunSummary::termination), without the summary's work (which reads the output files).
  [[nodiscard]] Termination termination() const noexcept;
  /// The rows recorded so far (OutputSinks::in_memory; empty otherwise), in the scene's order of outputs, then
  /// "monitors" when the scene asks for them.
  [[nodiscard]] const std::vector<OutputTable>& tables() const;

 private:
  struct Run;
  std::unique_ptr<Run> run_;
};

/// The run summary as fbsim --json prints it (one JSON object; docs/scenes.md lists its fields), for the scene file
/// `scene_file`.
[[nodiscard]] std::string summary_json(const Simulation& simulation, const std::string& scene_file);

/// The run summary as fbsim prints it (lines of text, each ending in a newline): steps, iterations and CPU time, the
/// steps' control, the initial assembly, redundant rows, time per step, energy and constraints, the files written;
/// `directory` is the run's output folder, `end_checkpoint` whether a checkpoint was written at the end.
[[nodiscard]] std::string summary_text(const Simulation& simulation, const std::filesystem::path& directory,
                                       bool end_checkpoint);

}  // namespace flexbody::scene
