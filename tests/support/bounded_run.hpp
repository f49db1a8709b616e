#pragma once
// Running a tool with a time limit and telling how it ended: an exit code, a signal, or the limit hit. For
// tests that feed damaged input, where a crash or a hang is the failure being looked for.

#include <chrono>
#include <csignal>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace flexbody::test {

struct BoundedRun {
  int exit_code = -1;      ///< when the tool exited by itself
  int signal = 0;          ///< the signal that killed it, 0 if none (SIGKILL after the time limit: timed_out)
  bool timed_out = false;  ///< still running at the limit, then killed
  std::chrono::duration<double> elapsed{0};
  std::string out, err;
};

/// Runs `executable ARGUMENTS` (no shell) with stdout and stderr captured in `output_stem`.out and .err, and
/// kills it once `limit` has passed.
/// `interrupt_when`: when given, asked every 2 ms while the tool runs; the first time it is true the tool gets
/// `signal`, as a user's Ctrl-C or a batch system's time limit would send it.
[[nodiscard]] BoundedRun run_bounded(const std::string& executable, const std::vector<std::string>& arguments,
                                     const std::filesystem::path& output_stem, std::chrono::duration<double> limit,
                                     const std::function<bool()>& interrupt_when = {}, int signal = SIGTERM);

}  // namespace flexbody::test
