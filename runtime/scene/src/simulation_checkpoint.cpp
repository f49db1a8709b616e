// Simulation's checkpoints: what a run saves besides the integrator's state and history (its counters, the
// conservation checks' baselines, each output file's length and each series' frames), the identity of the scene and
// of its body files, and the resume of the output files.
#include "simulation_run.hpp"

#include "flexbody/format/body_file.hpp"
#include "flexbody/format/checkpoint_file.hpp"

#include <sstream>
#include <system_error>

namespace flexbody::scene {
namespace {

using Entries = std::map<std::string, std::vector<double>>;

// The layout of "run.counts" (exact integers and flags) and "run.values".
enum Count { kCount, kSteps, kIterations, kConservationWarnings, kValidityWarnings, kEnergyWarned, kMomentumWarned,
             kWritten, kDrawn, kCsvFiles, kSeries, kCountSize };
enum Value { kCpu, kEnergyInitial, kEnergyFinal, kResidual, kEnergyGrowth, kMomentumGrowth, kExchanged, kLargestChange,
             kEnergyTerms, kMomentumInitial, kMomentumTerms, kNextRow, kNextFrame, kWallNs, kIntegratorNs, kValueSize };

std::string joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += line + '\n';
  return text;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

constexpr const char* kProgram = "fbsim " FLEXBODY_PACKAGE_VERSION;

std::string short_digest(const std::string& hex) { return hex.empty() ? "none (no seal)" : hex.substr(0, 12) + "..."; }

}  // namespace

CsvFile::CsvFile(const std::filesystem::path& path, std::uintmax_t bytes) : path_(path) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (error) throw CheckpointMismatch(path.string() + ": an output of the checkpoint's run is missing (" + error.message() + ")");
  if (size < bytes)
    throw CheckpointMismatch(fmt::format("{}: has {} bytes, fewer than the {} it had at the checkpoint: not the "
                                         "directory this checkpoint's run wrote", path.string(), size, bytes));
  std::filesystem::resize_file(path, bytes, error);  // the rows after the checkpoint go: the run writes them again
  if (error) throw std::runtime_error(path.string() + ": cannot cut it back to the checkpoint: " + error.message());
  out_.open(path, std::ios::app);
  if (!out_) throw std::runtime_error(path.string() + ": cannot write");
}

void Simulation::Run::check_identity(const format::CheckpointData& in, const std::filesystem::path& label) {
  auto text = [&](const std::string& name) -> const std::string& {
    const auto found = in.texts.find(name);
    if (found == in.texts.end()) throw CheckpointMismatch(label.string() + ": not a checkpoint of fbsim (no " + name + ")");
    return found->second;
  };
  // Another version's numbers may differ in their last bits (a change of the integrator). Only the version is
  // compared: a rebuild of the same version with another compiler is not caught.
  if (text("identity.program") != kProgram)
    throw CheckpointMismatch(fmt::format("{}: written by {}, this is {}: a run resumes with the fbsim that started it, "
                                         "or is run again from the start", label.string(), text("identity.program"), kProgram));
  if (text("identity.scene") != scene.source_sha256)
    throw CheckpointMismatch(fmt::format("{}: written for another scene: the scene's SHA-256 was {}, it is {} now (a "
                                         "checkpoint continues the scene file it was written for, unchanged)",
                                         label.string(), short_digest(text("identity.scene")),
                                         short_digest(scene.source_sha256)));
  const std::vector<std::string>& digests = scene.body_sha256;
  const std::vector<std::string> then = lines_of(text("identity.bodies"));
  for (std::size_t k = 0; k < digests.size() && k < scene.body_files.size(); ++k) {
    const std::string before = k < then.size() ? then[k] : std::string();
    if (before != digests[k])
      throw CheckpointMismatch(fmt::format("{}: written with another body file: {} has SHA-256 {} now, {} then",
                                           label.string(), scene.body_files[k].string(), short_digest(digests[k]),
                                           short_digest(before)));
  }
  if (then.size() != digests.size())
    throw CheckpointMismatch(fmt::format("{}: written for a scene of {} body files, this one has {}", label.string(),
                                         then.size(), digests.size()));
}

void Simulation::Run::save(format::CheckpointData& out) const {
  out.time = integrator->time();
  integrator->save(out);
  std::vector<double> counts(kCountSize), values(kValueSize);
  counts[kCount] = static_cast<double>(count);
  counts[kSteps] = static_cast<double>(summary.steps);
  counts[kIterations] = static_cast<double>(summary.newton_iterations);
  counts[kConservationWarnings] = static_cast<double>(summary.conservation_warnings);
  counts[kValidityWarnings] = static_cast<double>(summary.validity_warnings);
  counts[kEnergyWarned] = energy_warned;
  counts[kMomentumWarned] = momentum_warned;
  counts[kWritten] = written;
  counts[kDrawn] = drawn;
  counts[kCsvFiles] = static_cast<double>(files.size() + (monitors ? 1 : 0));
  counts[kSeries] = static_cast<double>(series.size());
  values[kCpu] = summary.cpu_seconds;
  values[kEnergyInitial] = summary.energy_initial;
  values[kEnergyFinal] = summary.energy_final;
  values[kResidual] = summary.max_constraint_residual;
  values[kEnergyGrowth] = summary.energy_growth;
  values[kMomentumGrowth] = summary.angular_momentum_growth;
  values[kExchanged] = exchanged;
  values[kLargestChange] = largest_change;
  values[kEnergyTerms] = energy_terms;
  values[kMomentumInitial] = momentum_initial;
  values[kMomentumTerms] = momentum_terms;
  values[kNextRow] = next_row;
  values[kNextFrame] = next_frame;
  values[kWallNs] = static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(wall).count());
  values[kIntegratorNs] = static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(in_integrator).count());
  out.numbers["run.counts"] = counts;
  out.numbers["run.values"] = values;
  out.texts["run.warnings"] = joined(summary.warnings);
  std::vector<double>& csv = out.numbers["output.csv_bytes"];
  auto length = [](const CsvFile& file) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(file.path(), error);
    if (error) throw std::runtime_error(file.path().string() + ": cannot read its size for the checkpoint: " + error.message());
    return static_cast<double>(size);
  };
  for (const auto& file : files) csv.push_back(length(*file));
  if (monitors) csv.push_back(length(*monitors));
  std::vector<double>& bytes = out.numbers["output.paraview_bytes"];
  for (std::size_t k = 0; k < series.size(); ++k) {
    out.numbers[fmt::format("output.paraview.{}", k)] = series[k].frame_times();
    bytes.push_back(series[k].bytes_written());
  }
  out.texts["identity.scene"] = scene.source_sha256;
  out.texts["identity.bodies"] = joined(scene.body_sha256);
  out.texts["identity.program"] = kProgram;
}

void Simulation::Run::restore(const format::CheckpointData& in, const std::filesystem::path& label) {
  auto entry = [&](const std::string& name, std::size_t size) -> const std::vector<double>& {
    const auto found = in.numbers.find(name);
    if (found == in.numbers.end()) throw CheckpointMismatch(label.string() + ": not a checkpoint of fbsim (no " + name + ")");
    if (found->second.size() != size)
      throw CheckpointMismatch(fmt::format("{}: {} has {} values, this scene's run {}", label.string(), name,
                                           found->second.size(), size));
    return found->second;
  };
  const std::vector<double>& counts = entry("run.counts", kCountSize);
  const std::vector<double>& values = entry("run.values", kValueSize);
  const std::size_t csv_files = scene.sensors.size() + (scene.monitors ? 1 : 0);
  if (counts[kCsvFiles] != static_cast<double>(csv_files) || counts[kSeries] != static_cast<double>(series.size()))
    throw CheckpointMismatch(fmt::format("{}: written for a run of {} CSV files and {} ParaView series, this one has {} "
                                         "and {}", label.string(), counts[kCsvFiles], counts[kSeries], csv_files,
                                         series.size()));
  const std::vector<double>& csv = entry("output.csv_bytes", csv_files);
  const std::vector<double>& bytes = entry("output.paraview_bytes", series.size());
  std::vector<const std::vector<double>*> frames;
  for (std::size_t k = 0; k < series.size(); ++k) {
    const std::string name = fmt::format("output.paraview.{}", k);
    const auto found = in.numbers.find(name);
    if (found == in.numbers.end()) throw CheckpointMismatch(label.string() + ": not a checkpoint of fbsim (no " + name + ")");
    frames.push_back(&found->second);
  }
  // Every file checked before any is changed: a refused resume leaves the directory as it was.
  for (std::size_t k = 0; k < csv_files; ++k) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(summary.files[k], error);
    if (error)
      throw CheckpointMismatch(fmt::format("{}: an output of the checkpoint's run is missing ({})", summary.files[k].string(),
                                           error.message()));
    if (static_cast<double>(size) < csv[k])
      throw CheckpointMismatch(fmt::format("{}: has {} bytes, fewer than the {} it had at the checkpoint: not the "
                                           "directory this checkpoint's run wrote", summary.files[k].string(), size, csv[k]));
  }
  for (std::size_t k = 0; k < series.size(); ++k)
    if (const std::string missing = series[k].missing_frame(*frames[k]); !missing.empty())
      throw CheckpointMismatch(missing + ": a frame of the checkpoint's series is missing");
  for (std::size_t k = 0; k < scene.sensors.size(); ++k)
    files.push_back(std::make_unique<CsvFile>(summary.files[k], static_cast<std::uintmax_t>(csv[k])));
  if (scene.monitors)
    monitors = std::make_unique<CsvFile>(summary.files[scene.sensors.size()], static_cast<std::uintmax_t>(csv.back()));
  for (std::size_t k = 0; k < series.size(); ++k) series[k].resume(*frames[k], bytes[k]);
  count = static_cast<long>(counts[kCount]);
  summary.steps = static_cast<long>(counts[kSteps]);
  summary.newton_iterations = static_cast<long>(counts[kIterations]);
  summary.conservation_warnings = static_cast<std::size_t>(counts[kConservationWarnings]);
  summary.validity_warnings = static_cast<std::size_t>(counts[kValidityWarnings]);
  energy_warned = counts[kEnergyWarned] != 0.0;
  momentum_warned = counts[kMomentumWarned] != 0.0;
  written = counts[kWritten] != 0.0;
  drawn = counts[kDrawn] != 0.0;
  summary.cpu_seconds = values[kCpu];
  summary.energy_initial = values[kEnergyInitial];
  summary.energy_final = values[kEnergyFinal];
  summary.max_constraint_residual = values[kResidual];
  summary.energy_growth = values[kEnergyGrowth];
  summary.angular_momentum_growth = values[kMomentumGrowth];
  exchanged = values[kExchanged];
  largest_change = values[kLargestChange];
  energy_terms = values[kEnergyTerms];
  momentum_initial = values[kMomentumInitial];
  momentum_terms = values[kMomentumTerms];
  next_row = values[kNextRow];
  next_frame = values[kNextFrame];
  wall = std::chrono::nanoseconds(static_cast<long long>(values[kWallNs]));
  in_integrator = std::chrono::nanoseconds(static_cast<long long>(values[kIntegratorNs]));
  const auto warnings = in.texts.find("run.warnings");
  if (warnings != in.texts.end()) summary.warnings = lines_of(warnings->second);
  checkpoint_time = integrator->time();
  summary.resumed_at = integrator->time();
}

void Simulation::Run::write_checkpoint() {
  flush();  // the CSV files' lengths are what is on disk
  format::CheckpointData data;
  data.created_by = kProgram;
  save(data);
  format::write_checkpoint_file(data, *checkpoint_file);
  checkpoint_time = integrator->time();
  last_checkpoint = std::chrono::steady_clock::now();
}

void Simulation::Run::checkpoint_when_due() {
  if (!scene.checkpoint_interval || !checkpoint_file) return;
  const double since = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_checkpoint).count();
  if (since < *scene.checkpoint_interval) return;
  try {
    write_checkpoint();
  } catch (const std::exception& e) {
    // A full disk must not end a run that can go on: said once, tried again after the next interval.
    last_checkpoint = std::chrono::steady_clock::now();
    if (!checkpoint_failed) {
      checkpoint_failed = true;
      warning(fmt::format("t = {:.6g} s: the checkpoint could not be written ({}); the run goes on, and tries again "
                          "every interval", integrator->time(), e.what()));
    }
  }
}

}  // namespace flexbody::scene
