#pragma once
// simulation_run.hpp (private): Simulation's state (simulation.cpp runs it, simulation_checkpoint.cpp saves and
// restores it) and its CSV files.

#include "flexbody/scene/simulation.hpp"

#include "flexbody/runtime/paraview_series.hpp"

#include <fmt/format.h>

#include <chrono>
#include <exception>
#include <fstream>

namespace flexbody::format {
struct CheckpointData;
}

namespace flexbody::scene {

// One CSV file per output; values with 17 significant digits (round-trip exact).
class CsvFile {
 public:
  CsvFile(const std::filesystem::path& path, const std::vector<std::string>& columns) : path_(path), out_(path) {
    if (!out_) throw std::runtime_error(path.string() + ": cannot write");
    out_ << "t [s]";
    for (const std::string& c : columns) out_ << ',' << c;
    out_ << '\n';
  }
  void row(double t, const Eigen::VectorXd& values) {
    out_ << fmt::format("{:.17g}", t);
    for (Eigen::Index k = 0; k < values.size(); ++k) out_ << fmt::format(",{:.17g}", values(k));
    out_ << '\n';
  }
  void flush() { out_.flush(); }
  /// Continues the file of a stopped run (a checkpoint's) after its first `bytes` bytes, which are kept; what a run
  /// wrote after them goes. Throws std::runtime_error naming the file if it is missing or shorter.
  CsvFile(const std::filesystem::path& path, std::uintmax_t bytes);
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::ofstream out_;
};

struct Simulation::Run {
  Scene scene;
  std::unique_ptr<runtime::GeneralizedAlpha> integrator;
  std::function<void(const std::string&)> warn;
  std::vector<std::unique_ptr<CsvFile>> files;  // per output (empty without a directory), then monitors.csv
  std::unique_ptr<CsvFile> monitors;
  std::vector<runtime::ParaViewSeries> series;
  std::vector<OutputTable> tables;  // OutputSinks::in_memory: per output, then the monitors
  bool in_memory = false;
  RunSummary summary;
  long count = 0;               // steps since the start: output_every and paraview_every count them
  bool written = true, drawn = true;  // the last completed step is recorded, drawn
  std::chrono::steady_clock::duration wall{}, in_integrator{};
  // The drift's scale: the largest kinetic + elastic + spring energy of the run (independent of where the gravity
  // potential is zero); and the magnitudes of the terms summed in E and L (the gravity potential depends on where
  // its zero is; |L_0| may be round-off of a body that only translates).
  double exchanged = 0.0, largest_change = 0.0, energy_terms = 0.0;
  double momentum_initial = 0.0, momentum_terms = 0.0;
  bool energy_warned = false, momentum_warned = false;
  double next_row = 0.0, next_frame = 0.0;  // output_interval, paraview_interval: the next times to record

  // Checkpoints (simulation_checkpoint.cpp): DIR/checkpoint.h5 with a directory, every scene.checkpoint_interval
  // seconds of wall-clock time; the scene's and its body files' identity, computed once.
  std::optional<std::filesystem::path> checkpoint_file;
  std::chrono::steady_clock::time_point last_checkpoint;
  std::optional<double> checkpoint_time;  // the simulated time of the last checkpoint written
  bool checkpoint_failed = false;  // a periodic checkpoint failed (said once)

  void record();
  void draw();
  void check();
  void baseline();
  [[nodiscard]] OutputEstimate estimate(double end) const;
  [[nodiscard]] bool due(const std::optional<double>& interval, int every, double& next) const;
  [[nodiscard]] double time_slack(double t) const;
  [[nodiscard]] double next_multiple(double interval, double t) const;
  void reschedule();
  void advance(bool to_end, double end, bool last);
  void recover();  // after a failed step: the last completed step recorded and drawn
  /// The summary's termination and its reason (empty but for a failure or an error).
  void ended(Termination how, std::string why = {});
  /// The same for the exception that ended a step: step_failed for runtime::StepFailure, stopped for RunInterrupted,
  /// else error, with its message.
  void ended_by_exception(const std::exception_ptr& reason);
  void start(Scene s, const OutputSinks& sinks, std::function<void(const std::string&)> w,
             const format::CheckpointData* from, const std::filesystem::path& label = {});
  /// Refuses (CheckpointMismatch) a checkpoint of another scene file or body file, or of another fbsim.
  void check_identity(const format::CheckpointData& in, const std::filesystem::path& label);
  void save(format::CheckpointData& out) const;
  void restore(const format::CheckpointData& in, const std::filesystem::path& label);
  void write_checkpoint();
  void checkpoint_when_due();  // after a step: when the interval has passed since the last one
  void flush() {
    for (auto& f : files) f->flush();
    if (monitors) monitors->flush();
  }
  void warning(std::string line) {
    summary.warnings.push_back(std::move(line));
    if (warn) warn(summary.warnings.back());
  }
};


}  // namespace flexbody::scene
