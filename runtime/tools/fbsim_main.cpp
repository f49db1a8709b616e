// fbsim: runs a scene of flexible (improved GCMS) and rigid bodies and writes what it asks for.
//
//   fbsim scene.yaml [-o DIR] [--json] [-q] [--resume DIR]
//
// main reads as its steps: parse the command line, choose the output directory, read the scene, run it and report.
#include "flexbody/format/body_file.hpp"
#include "flexbody/scene/scene.hpp"
#include "flexbody/scene/simulation.hpp"

#include "flexbody/runtime/threads.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <unistd.h>

namespace {

constexpr int kBadInput = 2, kFailed = 1;

// The signal that asked the run to stop (SIGINT, SIGTERM, SIGHUP), 0 while none did: the run stops after the step in
// progress and writes a checkpoint. The handler is reset once it ran, so that a second Ctrl-C ends fbsim at once.
volatile std::sig_atomic_t stop_signal = 0;

extern "C" void request_stop(int signal) { stop_signal = signal; }

void stop_on_signals() {
  struct sigaction action {};
  action.sa_handler = request_stop;
  action.sa_flags = SA_RESETHAND | SA_RESTART;  // no EINTR in the writes a step makes
  sigemptyset(&action.sa_mask);
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction before {};
    // A signal the process was started ignoring (nohup, a background job's SIGINT) stays ignored.
    if (sigaction(signal, nullptr, &before) == 0 && before.sa_handler == SIG_IGN) continue;
    sigaction(signal, &action, nullptr);
  }
}

const char* signal_name(int signal) { return signal == SIGINT ? "SIGINT (Ctrl-C)" : signal == SIGTERM ? "SIGTERM" : "SIGHUP"; }

// "42 s", "7.5 min", "3.2 h": a time to go as people read it.
std::string duration_text(double seconds) {
  if (seconds < 90.0) return fmt::format("{:.0f} s", seconds);
  if (seconds < 5400.0) return fmt::format("{:.1f} min", seconds / 60.0);
  return fmt::format("{:.1f} h", seconds / 3600.0);
}

// fbsim's one error line; the exit code goes up to main as an Exit.
struct Exit {
  int code;
};

[[noreturn]] void fail(const std::string& message, int code) {
  std::cerr << "fbsim: error: " << message << '\n';
  throw Exit{code};
}

namespace scene = flexbody::scene;

// What the command line asks for.
struct Invocation {
  std::filesystem::path scene_path;
  std::string output, resume, max_output;
  bool json = false, quiet = false;
  std::optional<double> end_time;
  int threads = 1;
  std::filesystem::path directory;  ///< where the run writes: -o, --resume's, or <scene name>_results
};

Invocation parse(int argc, char** argv) {
  CLI::App app{"fbsim: simulate a scene of flexible and rigid bodies (improved GCMS, generalized-alpha)."};
  Invocation in;
  std::string scene_file;
  app.add_option("SCENE", scene_file, "scene file (YAML)")->required();
  app.add_option("-o,--output", in.output, "directory for the CSV files (default: <scene name>_results, here)");
  app.add_flag("--json", in.json, "print the run summary as one JSON object on stdout");
  app.add_flag("-q,--quiet", in.quiet, "no progress and no summary (errors still go to stderr)");
  app.add_option("--end", in.end_time,
                 "end time [s] instead of the scene's integrator end (a shorter trial run, or a "
                 "longer one); refused below the integrator step");
  app.add_option("--max-output", in.max_output,
                 "the most the run may write into its output directory, e.g. 50GB "
                 "(default 10 GB and 100000 files; the scene's output_budget sets "
                 "both); a run estimated over it is refused before its first step");
  app.add_option("--resume", in.resume,
                 "continue the run whose outputs and checkpoint.h5 are in DIR (written when it "
                 "was stopped, or by the scene's checkpoint: {interval}), with the same scene "
                 "and body files; its outputs come out as an uninterrupted run's, bit for bit")
      ->type_name("DIR");
  app.add_option(
         "--threads", in.threads,
         "threads for the per-body work of scenes of 64 bodies and more (default 1: with the cores shared, more "
         "threads are far slower; results are the same bits for any count)")
      ->check(CLI::Range(1, 1024));
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    throw Exit{app.exit(e)};
  } catch (const CLI::ParseError& e) {
    fail(std::string(e.what()) + " (see fbsim --help)", kBadInput);
  }
  in.scene_path = scene_file;
  return in;
}

// The output directory, checked before anything is read or run: --resume's must hold a checkpoint (and be -o's, if
// both are given), and an existing file is never a directory to write into.
void choose_directory(Invocation& in) {
  if (!in.resume.empty()) {
    // The error_code overloads: a directory that cannot be read is a refusal, not an abort.
    std::error_code resume_error, output_error, file_error;
    if (!in.output.empty() && std::filesystem::weakly_canonical(in.resume, resume_error) !=
                                  std::filesystem::weakly_canonical(in.output, output_error))
      fail(fmt::format("--resume {} and -o {}: a run resumes in its own output directory; give one of them", in.resume,
                       in.output),
           kBadInput);
    if (resume_error || output_error)
      fail(fmt::format("--resume {}: {}", in.resume, (resume_error ? resume_error : output_error).message()),
           kBadInput);
    const bool found =
        std::filesystem::is_regular_file(std::filesystem::path(in.resume) / scene::kCheckpointFileName, file_error);
    if (!found)  // a missing file is the usual case, said without the system's "No such file or directory"
      fail(fmt::format("--resume {}: no {} there{} (a run writes it when it is stopped, or every interval of the "
                       "scene's checkpoint key)",
                       in.resume, scene::kCheckpointFileName,
                       file_error && file_error != std::errc::no_such_file_or_directory
                           ? " (" + file_error.message() + ")"
                           : ""),
           kBadInput);
  }
  in.directory = !in.resume.empty()  ? std::filesystem::path(in.resume)
                 : in.output.empty() ? std::filesystem::path(in.scene_path.stem().string() + "_results")
                                     : std::filesystem::path(in.output);
  if (std::error_code error;
      std::filesystem::exists(in.directory, error) && !std::filesystem::is_directory(in.directory, error)) {
    const std::string origin = in.output.empty() ? fmt::format(
                                                       "{} (the default output directory: the scene's name + "
                                                       "_results)",
                                                       in.directory.string())
                                                 : fmt::format("-o {}", in.directory.string());
    fail(fmt::format("{}: is an existing file, not a directory; choose another output directory with -o", origin),
         kBadInput);
  }
}

// The scene file with the command line's overrides (--end, --max-output).
scene::Scene read_scene_file(const Invocation& in) {
  scene::SceneOverrides overrides;
  overrides.end_time = in.end_time;
  if (!in.max_output.empty()) {
    try {
      overrides.max_output = scene::parse_size(in.max_output);
    } catch (const std::invalid_argument& e) {
      fail(fmt::format("--max-output: {}", e.what()), kBadInput);
    }
  }
  try {
    return scene::read_scene(in.scene_path, overrides);
  } catch (const std::invalid_argument& e) {
    fail(e.what(), kBadInput);
  } catch (const std::exception& e) {
    fail(e.what(), kFailed);
  }
}

// Runs the scene to its end (or resumes it) and prints the summary; returns the exit code (128 + a signal's number
// for a run a signal stopped, after its checkpoint).
int run(const Invocation& in, scene::Scene read) {
  const std::filesystem::path& scene_path = in.scene_path;
  const std::filesystem::path& directory = in.directory;
  const bool json = in.json, quiet = in.quiet;
  const std::string& resume = in.resume;
  const double end = read.end_time;
  const bool terminal = !quiet && !json && ::isatty(STDERR_FILENO);
  // On a terminal: the simulated time, steps per second and the time to go (at the rate so far), every 100 steps.
  const double step = read.integrator.step;
  std::chrono::steady_clock::time_point started;  // set when the steps begin (after the assembly and the first frame)
  double start_time = 0.0;                        // and the simulated time then (a resumed run's is not 0)
  auto progress = [&](double t) {
    if (!terminal) return;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    const double rate = (t - start_time) / step / std::max(seconds, 1e-9);
    std::cerr << fmt::format("\r  t = {:.4g} / {:.4g} s, {:.0f} steps/s, {} to go   ", t, end, rate,
                             duration_text((end - t) / step / rate))
              << std::flush;
  };
  const bool checkpoints = read.checkpoint_interval.has_value();
  bool end_checkpoint = false;  // written at the end (checkpoints)
  std::unique_ptr<flexbody::scene::Simulation> simulation;
  // A checkpoint at a stop; one that cannot be written is said, and does not hide why the run stopped.
  auto checkpoint_at_stop = [&]() -> std::string {
    try {
      const std::filesystem::path written = simulation->checkpoint();
      return fmt::format("; checkpoint {} at t = {:.6g} s: continue with fbsim {} --resume {}", written.string(),
                         simulation->time(), scene_path.string(), directory.string());
    } catch (const std::exception& e) {
      return fmt::format("; no checkpoint: {}", e.what());
    }
  };
  // The run's summary on stdout; after a failure, one that cannot be made (its files unreadable) is left out rather
  // than hide the failure's line.
  auto print_summary = [&](bool with_end_checkpoint) {
    try {
      if (json)
        std::cout << flexbody::scene::summary_json(*simulation, scene_path.string()) << '\n';
      else if (!quiet)
        std::cout << flexbody::scene::summary_text(*simulation, directory, with_end_checkpoint);
      std::cout.flush();
    } catch (const std::exception& e) {
      std::cerr << fmt::format("fbsim: warning: no summary: {}\n", e.what());
    }
  };
  try {
    auto warn = [terminal](const std::string& line) {  // even with -q: a broken conservation law is not progress
      if (terminal) std::cerr << '\n';
      std::cerr << "fbsim: warning: " << line << '\n';
    };
    const flexbody::scene::OutputSinks sinks{directory, false};
    if (resume.empty())
      simulation = std::make_unique<flexbody::scene::Simulation>(std::move(read), sinks, warn);
    else
      simulation = std::make_unique<flexbody::scene::Simulation>(
          std::move(read), sinks, flexbody::scene::Resume{directory / flexbody::scene::kCheckpointFileName}, warn);
    stop_on_signals();
    started = std::chrono::steady_clock::now();
    start_time = simulation->time();
    if (!simulation->run(end, progress, [] { return stop_signal != 0; })) {
      // A second signal while the checkpoint is written ends fbsim at once, without leaving its temporary file.
      flexbody::format::remove_temporary_body_file_on_signal();
      if (terminal) std::cerr << '\n';
      const int signal = stop_signal;
      std::cerr << fmt::format("fbsim: stopped by {} at t = {:.6g} s{}\n", signal_name(signal), simulation->time(),
                               checkpoint_at_stop());
      // Ended by the signal, as the shell expects of a program it interrupted (a script's next command then does not
      // run after Ctrl-C); the exit status is 128 + its number.
      std::cout.flush();
      std::raise(signal);
      return 128 + signal;
    }
    // The end's checkpoint, from which a later --resume --end runs on; without checkpoints, one left by a stop before a
    // --resume no longer matches the files (it would cut them back).
    if (checkpoints) {
      try {
        simulation->checkpoint();
        end_checkpoint = true;
      } catch (const std::exception& e) {  // the run itself is complete: said, and the exit code stays 0
        std::cerr << fmt::format("fbsim: warning: the checkpoint at the end could not be written: {}\n", e.what());
      }
    } else if (std::error_code ignored; !resume.empty()) {
      std::filesystem::remove(directory / flexbody::scene::kCheckpointFileName, ignored);
    }
  } catch (const flexbody::scene::OutputBudgetError& e) {  // before the first step, naming the scene's lines
    fail(e.what(), kBadInput);
  } catch (const flexbody::scene::CheckpointMismatch& e) {  // --resume with a checkpoint of another scene or directory
    fail(e.what(), kBadInput);
  } catch (const flexbody::format::BodyFileError& e) {  // --resume with a damaged or foreign checkpoint file
    fail(e.what(), kBadInput);
  } catch (const flexbody::runtime::StepFailure& e) {
    if (terminal) std::cerr << '\n';
    if (simulation) print_summary(false);  // what the run did up to the failed step; its termination names it
    fail(fmt::format("{}: {} (outputs up to the last completed step are in {}{})", scene_path.string(), e.what(),
                     directory.string(), checkpoints ? checkpoint_at_stop() : std::string()),
         kFailed);
  } catch (const std::invalid_argument& e) {  // the assembled scene is inconsistent (before any step or file)
    fail(fmt::format("{}: {}", scene_path.string(), e.what()), kBadInput);
  } catch (const std::exception& e) {
    // A scene's own function (a force's) that threw during a step: the run so far, then why it ended.
    if (simulation && simulation->termination() == flexbody::scene::Termination::error) print_summary(false);
    fail(fmt::format("{}: {}", scene_path.string(), e.what()), kFailed);
  }
  if (terminal) std::cerr << '\n';
  print_summary(end_checkpoint);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  flexbody::format::skip_hdf5_cleanup_at_exit();  // one error line, nothing from HDF5 after it
  try {
    Invocation in = parse(argc, argv);
    flexbody::runtime::set_threads(in.threads);
    choose_directory(in);
    return run(in, read_scene_file(in));
  } catch (const Exit& exit) {
    return exit.code;
  }
}
