#include "flexbody/scene/simulation.hpp"

#include "output_values.hpp"
#include "simulation_run.hpp"

#include "flexbody/format/checkpoint_file.hpp"
#include "flexbody/runtime/gcms_elastic.hpp"
#include "flexbody/runtime/paraview_series.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <utility>

namespace flexbody::scene {
namespace {

// The scales that E(t) − E_0 and |L(t)| − |L_0| round relative to are at least this fraction of the magnitudes of
// the terms summed in them, so that round-off never warns.
constexpr double kRoundOffScale = 1e-9;

// CPU seconds since `start`.
double cpu_since(std::clock_t start) { return static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC; }

}  // namespace

void Simulation::Run::record() {
  const double t = integrator->time();
  for (std::size_t k = 0; k < scene.sensors.size(); ++k) {
    const Eigen::VectorXd values = values_of(scene, scene.sensors[k], *integrator);
    if (!files.empty()) files[k]->row(t, values);
    if (in_memory) {
      tables[k].times.push_back(t);
      tables[k].values.insert(tables[k].values.end(), values.data(), values.data() + values.size());
    }
  }
  if (scene.monitors) {
    const Eigen::VectorXd values = monitor_values(scene, *integrator);
    if (monitors) monitors->row(t, values);
    if (in_memory) {
      tables.back().times.push_back(t);
      tables.back().values.insert(tables.back().values.end(), values.data(), values.data() + values.size());
    }
  }
}

void Simulation::Run::draw() {  // each series once per time, also when called again after one of them failed
  for (std::size_t k = 0; k < series.size(); ++k)
    if (series[k].last_time() != integrator->time())
      series[k].write(integrator->time(),
                      runtime::gcms_coordinates(scene.system.model(scene.paraview[k].body),
                                                scene.system.body_coordinates(integrator->coordinates(), scene.paraview[k].body)));
}

// Energies, residuals and momenta at a checked step; a conservation law broken beyond kConservationTolerance is
// reported once, when it first happens.
void Simulation::Run::check() {
  const runtime::System& system = scene.system;
  const Eigen::VectorXd& q = integrator->coordinates();
  const Eigen::VectorXd& v = integrator->velocities();
  const double t = integrator->time();
  summary.max_constraint_residual =
      std::max(summary.max_constraint_residual, system.constraints(t, q).cwiseAbs().maxCoeff());
  const runtime::Energies e = system.energies(q, v);
  exchanged = std::max(exchanged, e.kinetic + e.elastic + e.springs);
  largest_change = std::max(largest_change, std::abs(e.total() - summary.energy_initial));
  summary.energy_final = e.total();
  if (scene.conserves.energy) {
    energy_terms = std::max(energy_terms, std::abs(e.gravity) + e.kinetic + e.elastic + e.springs);
    const double growth =
        (e.total() - summary.energy_initial) / std::max({exchanged, kRoundOffScale * energy_terms, 1e-300});
    summary.energy_growth = std::max(summary.energy_growth, growth);  // the largest ratio tested, as warned
    if (!energy_warned && growth > kConservationTolerance) {
      energy_warned = true;
      ++summary.conservation_warnings;
      warning(fmt::format(
          "t = {:.6g} s: the energy of this conservative scene (no damping, no driven joint, no applied load) grew by "
          "{:.3g} % of its largest kinetic + elastic + spring energy (warning above {:.3g} %); generalized-alpha only "
          "dissipates, so the motion is not to be trusted: try a smaller step or a smaller rho_inf",
          t, 100.0 * growth, 100.0 * kConservationTolerance));
    }
  }
  if (scene.conserves.angular_momentum) {
    const AngularMomentum l = angular_momentum(system, q, v);
    momentum_terms = std::max(momentum_terms, l.terms);
    const double growth =
        (l.value.norm() - momentum_initial) / std::max({momentum_initial, kRoundOffScale * momentum_terms, 1e-300});
    summary.angular_momentum_growth = std::max(summary.angular_momentum_growth, growth);
    if (!momentum_warned && growth > kConservationTolerance) {
      momentum_warned = true;
      ++summary.conservation_warnings;
      warning(fmt::format(
          "t = {:.6g} s: the angular momentum about the centre of mass of this free, torque-free scene grew by "
          "{:.3g} % of its initial {:.6g} kg m^2/s (warning above {:.3g} %): the motion is not to be trusted; try a "
          "smaller step or a smaller rho_inf", t, 100.0 * growth, momentum_initial, 100.0 * kConservationTolerance));
    }
  }
}

// One step (to `end` exactly when `to_end`); `last`: the last of a run, recorded and checked whatever the counts say.
// Under error control (step: auto) one step toward the next row's or frame's time, or `end` when `to_end`: the last
// is the one that reaches it.
void Simulation::Run::advance(bool to_end, double end, bool last) {
  const auto start = std::chrono::steady_clock::now();
  if (scene.integrator.error_tolerance > 0.0) {
    double stop = to_end ? end : std::numeric_limits<double>::infinity();
    if (scene.output_interval) stop = std::min(stop, next_row);
    if (scene.paraview_interval) stop = std::min(stop, next_frame);
    integrator->step_toward(stop);
    last = last || (to_end && integrator->time() == end);
  } else if (to_end) {
    integrator->step_to(end);
  } else {
    integrator->step();
  }
  in_integrator += std::chrono::steady_clock::now() - start;
  written = drawn = false;
  ++count;
  ++summary.steps;
  summary.newton_iterations += integrator->last_iterations();
  // Both evaluated: each moves its next time.
  const bool row = due(scene.output_interval, scene.output_every, next_row);
  const bool frame = due(scene.paraview_interval, scene.paraview_every, next_frame);
  if (row || last) {
    record();
    written = true;
  }
  if (frame || last) {
    draw();
    drawn = true;
  }
  // The warnings last: a warn callback that throws (Python's warnings as errors) stops the run after the step is
  // counted and recorded.
  for (std::size_t w = summary.validity_warnings; w < integrator->warnings().size(); ++w) {  // the model's validity
    ++summary.validity_warnings;
    warning(integrator->warnings()[w]);
  }
  if (count % kCheckEvery == 0 || last) check();
  wall += std::chrono::steady_clock::now() - start;
}

// The CSV files' and the ParaView series' sizes for a run from t = 0 to `end` (output_budget.hpp).
OutputEstimate Simulation::Run::estimate(double end) const {
  const double steps = scene.integrator.error_tolerance > 0.0 ? std::numeric_limits<double>::infinity()  // by time
                                                              : step_count(end, scene.integrator.step);
  // Rows at t = 0, every n-th step, and at the end when it is not one of them.
  auto recorded = [steps, end](int every, const std::optional<double>& interval) {
    if (interval) {  // at most one row per step
      const double multiples = std::floor(end / *interval + 1e-9);
      return std::min(1.0 + multiples + (end - multiples * *interval > 1e-9 * *interval ? 1.0 : 0.0), 1.0 + steps);
    }
    return 1.0 + std::floor(steps / every) + (std::fmod(steps, every) != 0.0 ? 1.0 : 0.0);
  };
  constexpr double kValueBytes = 25.0;  // "%.17g" is at most 24 characters ("-1.2345678901234567e-100"), and its comma
  OutputEstimate e;
  double columns = 0.0, csv_files = 0.0;
  for (const Sensor& s : scene.sensors) {
    columns += 1.0 + static_cast<double>(columns_of(scene, s).size());
    csv_files += 1.0;
  }
  if (scene.monitors) {
    columns += 1.0 + static_cast<double>(monitor_columns().size());
    csv_files += 1.0;
  }
  if (csv_files > 0.0) {
    const double rows = recorded(scene.output_every, scene.output_interval);
    e.parts.push_back({fmt::format("CSV outputs ({:.0f} file{})", csv_files, csv_files == 1.0 ? "" : "s"), scene.outputs_at, rows,
                       rows * columns * kValueBytes, csv_files});
  }
  if (!series.empty()) {  // one part: the bodies' series are set by the same lines
    const double frames = recorded(scene.paraview_every, scene.paraview_interval);
    double bytes = 0.0;
    for (const runtime::ParaViewSeries& s : series)  // the frames and the collection (an entry per frame)
      bytes += frames * (s.frame_bytes() + 40.0 + 2.0 * static_cast<double>(s.collection().stem().string().size()));
    const std::string what = series.size() == 1
                                 ? fmt::format("paraview body '{}'", series.front().collection().stem().string())
                                 : fmt::format("paraview series of {} bodies", series.size());
    e.parts.push_back({what, scene.paraview_at, frames, bytes, static_cast<double>(series.size()) * (frames + 1.0)});
  }
  return e;
}

// Whether the step just taken records: every n-th step, or the first step at or after the next multiple of the
// interval. A time within the rounding of t0 + k h of a multiple counts as there (a millionth of a step, or 8 ε |t|
// far from zero), and the next multiple is the first after it.
bool Simulation::Run::due(const std::optional<double>& interval, int every, double& next) const {
  if (!interval) return count % every == 0;
  const double t = integrator->time();
  if (t < next - time_slack(t)) return false;
  next = next_multiple(*interval, t);
  return true;
}

double Simulation::Run::time_slack(double t) const {
  return std::max(1e-6 * scene.integrator.step, 8.0 * std::numeric_limits<double>::epsilon() * std::abs(t));
}

// The first multiple of `interval` after t (beyond its slack).
double Simulation::Run::next_multiple(double interval, double t) const {
  const double slack = time_slack(t);
  double k = std::floor((t + slack) / interval) + 1.0;
  while (k * interval <= t + slack) k += 1.0;  // floor's rounding at an exact multiple far from zero
  return k * interval;
}

// After the time was set (set_state): the next multiples after it.
void Simulation::Run::reschedule() {
  const double t = integrator->time();
  if (scene.output_interval) next_row = next_multiple(*scene.output_interval, t);
  if (scene.paraview_interval) next_frame = next_multiple(*scene.paraview_interval, t);
}

// The scales the conservation checks measure against, from the integrator's state (the start, or a state set).
void Simulation::Run::baseline() {
  const runtime::System& system = scene.system;
  const runtime::Energies e0 = system.energies(integrator->coordinates(), integrator->velocities());
  summary.energy_initial = summary.energy_final = e0.total();
  exchanged = e0.kinetic + e0.elastic + e0.springs;
  largest_change = 0.0;
  energy_terms = std::abs(e0.gravity) + e0.kinetic + e0.elastic + e0.springs;
  energy_warned = momentum_warned = false;
  if (scene.conserves.angular_momentum) {
    const AngularMomentum l0 = angular_momentum(system, integrator->coordinates(), integrator->velocities());
    momentum_initial = l0.value.norm();
    momentum_terms = l0.terms;
  }
}

// The last completed step, whatever output_every says; a failure to write it must not hide why the run stopped
// (the exception being handled), so it is dropped here.
void Simulation::Run::recover() {
  try {
    if (!written) record();
    written = true;
  } catch (const std::exception&) {
  }
  try {
    if (!drawn) draw();
    drawn = true;
  } catch (const std::exception&) {
  }
  flush();
}

void Simulation::Run::ended(Termination how, std::string why) {
  summary.termination = how;
  summary.termination_message = std::move(why);
}

void Simulation::Run::ended_by_exception(const std::exception_ptr& reason) {
  try {
    std::rethrow_exception(reason);
  } catch (const runtime::StepFailure& e) {
    ended(Termination::step_failed, e.what());
  } catch (const RunInterrupted& e) {
    ended(Termination::stopped, e.what());
  } catch (const std::exception& e) {
    ended(Termination::error, e.what());
  } catch (...) {
    ended(Termination::error, "an exception that is not a std::exception");
  }
}

Simulation::Simulation(Scene scene, const OutputSinks& sinks, std::function<void(const std::string&)> warn)
    : run_(std::make_unique<Run>()) {
  run_->start(std::move(scene), sinks, std::move(warn), nullptr);
}

Simulation::Simulation(Scene scene, const OutputSinks& sinks, const Resume& from, std::function<void(const std::string&)> warn)
    : run_(std::make_unique<Run>()) {
  if (!sinks.directory) throw std::logic_error("Simulation: a run resumes into its output directory; none was given");
  const format::CheckpointData checkpoint = format::read_checkpoint_file(from.checkpoint);
  run_->start(std::move(scene), sinks, std::move(warn), &checkpoint, from.checkpoint);
}

// The run from the start, or from a checkpoint (`from`, read from `label`): the integrator first, so that a scene
// whose initial state or constraints are inconsistent fails before any file; then the budget, before any file too.
void Simulation::Run::start(Scene s, const OutputSinks& sinks, std::function<void(const std::string&)> w,
                            const format::CheckpointData* from, const std::filesystem::path& label) {
  const std::clock_t cpu_start = std::clock();
  scene = std::move(s);
  warn = std::move(w);
  if (from) check_identity(*from, label);
  integrator = std::make_unique<runtime::GeneralizedAlpha>(scene.system, scene.integrator);
  if (from) {
    try {
      integrator->restore(*from);
    } catch (const std::invalid_argument& e) {
      throw CheckpointMismatch(fmt::format("{}: {}", label.string(), e.what()));
    }
  }
  summary.sparse = integrator->sparse();
  in_memory = sinks.in_memory;
  if (in_memory) {
    for (const Sensor& sensor : scene.sensors) tables.push_back({sensor.name, columns_of(scene, sensor), {}, {}});
    if (scene.monitors) tables.push_back({"monitors", monitor_columns(), {}, {}});
  }
  if (sinks.directory) {
    const std::filesystem::path& directory = *sinks.directory;
    for (const SurfaceSeries& series_of : scene.paraview)  // nothing is written before its first frame
      series.emplace_back(directory, scene.system.body_name(series_of.body), scene.system.model(series_of.body),
                          series_of.stresses);
    // What a run to the scene's end would write, checked before any file is made.
    const OutputEstimate estimated = estimate(scene.end_time);
    summary.estimated_bytes = estimated.bytes();
    summary.estimated_files = estimated.files();
    check_output_budget(estimated, scene.budget, scene.step_at);
    if (std::error_code error; !std::filesystem::create_directories(directory, error) && error)
      throw std::runtime_error(fmt::format("{}: cannot create the output directory: {}", directory.string(), error.message()));
    for (const Sensor& sensor : scene.sensors) summary.files.push_back(directory / (sensor.name + ".csv"));
    if (scene.monitors) summary.files.push_back(directory / "monitors.csv");
    for (const runtime::ParaViewSeries& one : series) summary.files.push_back(one.collection());
    checkpoint_file = directory / kCheckpointFileName;
    // A new run's files replace the directory's: a checkpoint left there by an earlier run would no longer match them.
    if (std::error_code ignored; !from) std::filesystem::remove(*checkpoint_file, ignored);
    if (from) {
      restore(*from, label);  // the files continued where the checkpoint left them
    } else {
      for (std::size_t k = 0; k < scene.sensors.size(); ++k)
        files.push_back(std::make_unique<CsvFile>(summary.files[k], columns_of(scene, scene.sensors[k])));
      if (scene.monitors) monitors = std::make_unique<CsvFile>(summary.files[scene.sensors.size()], monitor_columns());
    }
  }
  last_checkpoint = std::chrono::steady_clock::now();
  if (!from) {
    baseline();
    reschedule();
    record();
    draw();
  }
  summary.cpu_seconds += cpu_since(cpu_start);
}

Simulation::~Simulation() = default;

void Simulation::step() {
  const std::clock_t cpu_start = std::clock();
  try {
    run_->advance(false, 0.0, false);
    run_->checkpoint_when_due();
  } catch (...) {
    run_->recover();
    run_->summary.cpu_seconds += cpu_since(cpu_start);
    run_->ended_by_exception(std::current_exception());
    throw;
  }
  run_->summary.cpu_seconds += cpu_since(cpu_start);
  run_->ended(Termination::running);
}

bool Simulation::run(double end, const std::function<void(double)>& progress, const std::function<bool()>& stop) {
  Run& r = *run_;
  r.ended(Termination::running);
  const double now = r.integrator->time();
  const double h = r.scene.integrator.step;
  // A time that is `end` up to the rounding of t0 + k h (nine steps of 1e-3 s end at 0.009000000000000001) is there.
  const double slack = std::max(runtime::GeneralizedAlpha::kStepToSlack * h,
                                8.0 * std::numeric_limits<double>::epsilon() * std::abs(end));
  if (!std::isfinite(end) || end < now - slack)
    throw std::invalid_argument(fmt::format("run to t = {} s: the simulation is at t = {} s already", end, now));
  if (end <= now + slack) {
    r.ended(Termination::end_reached);
    return true;
  }
  // Fixed steps: whole steps, the last one shortened to end on `end` exactly (step_count), at most kMostSteps
  // (scene.hpp). Under error control (step: auto) the controller's steps, toward each row's and frame's time, until
  // one ends on `end`.
  const bool controlled = r.scene.integrator.error_tolerance > 0.0;
  long steps = 0;
  if (!controlled) {
    if ((end - now) / h > kMostSteps)
      throw std::invalid_argument(fmt::format("run to t = {} s: {:.3g} steps of {} s, more than a run may take ({:.0e})",
                                              end, (end - now) / h, h, kMostSteps));
    // end − now carries the rounding of both times (8 ε of each, in steps) besides step_count's own slack.
    const double span = (end - now) / h;
    const double rounding = 8.0 * std::numeric_limits<double>::epsilon() * (std::abs(now) + std::abs(end)) / h;
    steps = static_cast<long>(std::min(step_count(end - now, h), std::max(1.0, std::ceil(span - rounding))));
  }
  const std::clock_t cpu_start = std::clock();
  try {
    for (long k = 1;; ++k) {
      const bool last = !controlled && k == steps;
      r.advance(controlled || last, end, last);
      r.checkpoint_when_due();
      if (progress && k % 100 == 0) progress(r.integrator->time());
      if (controlled ? r.integrator->time() == end : last) break;
      if (stop && stop()) {
        r.flush();
        r.summary.cpu_seconds += cpu_since(cpu_start);
        r.ended(Termination::stopped);
        return false;
      }
    }
  } catch (...) {
    r.recover();
    r.summary.cpu_seconds += cpu_since(cpu_start);
    r.ended_by_exception(std::current_exception());
    throw;
  }
  r.flush();
  r.summary.cpu_seconds += cpu_since(cpu_start);
  r.ended(Termination::end_reached);
  return true;
}

std::filesystem::path Simulation::checkpoint() {
  if (!run_->checkpoint_file) throw std::logic_error("Simulation::checkpoint: the run has no output directory");
  run_->write_checkpoint();
  return *run_->checkpoint_file;
}

std::optional<double> Simulation::last_checkpoint() const { return run_->checkpoint_time; }

const Scene& Simulation::scene() const { return run_->scene; }
const runtime::GeneralizedAlpha& Simulation::integrator() const { return *run_->integrator; }
runtime::IntegratorState Simulation::state() const { return run_->integrator->state(); }
void Simulation::set_state(const runtime::IntegratorState& state) {
  run_->integrator->set_state(state);
  run_->ended(Termination::running);
  run_->baseline();
  run_->reschedule();
}
const std::vector<OutputTable>& Simulation::tables() const { return run_->tables; }

Termination Simulation::termination() const noexcept { return run_->summary.termination; }

const char* termination_name(Termination termination) {
  switch (termination) {
    case Termination::running:
      return "running";
    case Termination::end_reached:
      return "end reached";
    case Termination::stopped:
      return "stopped";
    case Termination::step_failed:
      return "step failed";
    case Termination::error:
      return "error";
  }
  return "running";
}

RunSummary Simulation::summary() const {
  run_->flush();  // the CSV files' sizes below are what is on disk
  RunSummary s = run_->summary;
  s.time = run_->integrator->time();
  s.newton_matrices = run_->integrator->factorizations();
  s.retried_steps = run_->integrator->retried_steps();
  s.rejected_steps = run_->integrator->rejected_steps();
  s.steps_above_tolerance = run_->integrator->steps_above_tolerance();
  s.largest_step = run_->scene.integrator.error_tolerance > 0.0 ? run_->integrator->largest_step()
                                                                  : run_->scene.integrator.step;
  s.smallest_step = std::isfinite(run_->integrator->smallest_step()) ? run_->integrator->smallest_step()
                                                                      : run_->scene.integrator.step;
  s.wall_seconds = std::chrono::duration<double>(run_->wall).count();
  s.integrator_wall_seconds = std::chrono::duration<double>(run_->in_integrator).count();
  s.energy_drift = run_->largest_change / std::max(run_->exchanged, 1e-300);
  s.energy_final = run_->scene.system.energies(run_->integrator->coordinates(), run_->integrator->velocities()).total();
  // What is on disk: the CSV files and collections by their sizes, the frames as counted when written.
  s.written_bytes = s.written_files = 0.0;
  for (const std::filesystem::path& file : s.files) {
    std::error_code unknown;
    const std::uintmax_t size = std::filesystem::file_size(file, unknown);
    s.written_bytes += unknown ? 0.0 : static_cast<double>(size);
    s.written_files += 1.0;
  }
  for (const runtime::ParaViewSeries& series : run_->series) {
    s.written_bytes += series.bytes_written();
    s.written_files += static_cast<double>(series.frame_count());
  }
  return s;
}

}  // namespace flexbody::scene
