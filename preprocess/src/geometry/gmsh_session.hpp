#pragma once
// A gmsh session for one import: initializes gmsh quietly, silences OpenCASCADE's own printing, and
// turns gmsh's errors (thrown as std::string by gmsh 4.8) into std::runtime_error. gmsh sets OpenMP's thread count
// to its General.NumThreads (1) when it starts: the session gives the process its count back when it ends, or every
// OpenMP loop after the import (assembly, stress recovery, Eigen's products) would run on one thread.

#include <stdexcept>
#include <string>
#include <utility>

namespace flexbody::preprocess::detail {

/// Redirects the process' stdout and stderr to /dev/null while alive (OpenCASCADE writes parse errors
/// straight to the terminal, which would break one-line errors and --json on stdout).
class SilencedStdStreams {
 public:
  SilencedStdStreams();
  ~SilencedStdStreams();
  SilencedStdStreams(const SilencedStdStreams&) = delete;
  SilencedStdStreams& operator=(const SilencedStdStreams&) = delete;

 private:
  int saved_stdout_ = -1;
  int saved_stderr_ = -1;
};

class GmshSession {
 public:
  GmshSession();
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
  /// OpenMP's thread count before gmsh set it to 1: what a parallel gmsh algorithm may use.
  [[nodiscard]] int threads() const { return threads_; }

 private:
  int threads_;  ///< omp_get_max_threads() before gmsh changed it
};

/// Calls `f` with gmsh's error type translated: std::runtime_error("<context>: <gmsh's message>").
template <typename F>
decltype(auto) gmsh_call(const std::string& context, F&& f) {
  try {
    return std::forward<F>(f)();
  } catch (const std::string& message) {
    throw std::runtime_error(context + ": " + message);
  }
}

}  // namespace flexbody::preprocess::detail
