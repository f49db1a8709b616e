#include "gmsh_session.hpp"

#include <gmsh.h>
#include <omp.h>

#include <cstdio>
#include <fcntl.h>
#include <unistd.h>

namespace flexbody::preprocess::detail {

SilencedStdStreams::SilencedStdStreams() {
  std::fflush(stdout);
  std::fflush(stderr);
  const int null = ::open("/dev/null", O_WRONLY);
  if (null < 0) return;
  saved_stdout_ = ::dup(STDOUT_FILENO);
  saved_stderr_ = ::dup(STDERR_FILENO);
  if (saved_stdout_ < 0 || saved_stderr_ < 0) {  // could not save them: better noisy than mute for good
    if (saved_stdout_ >= 0) ::close(saved_stdout_);
    if (saved_stderr_ >= 0) ::close(saved_stderr_);
    saved_stdout_ = saved_stderr_ = -1;
    ::close(null);
    return;
  }
  ::dup2(null, STDOUT_FILENO);
  ::dup2(null, STDERR_FILENO);
  ::close(null);
}

SilencedStdStreams::~SilencedStdStreams() {
  std::fflush(stdout);
  std::fflush(stderr);
  if (saved_stdout_ >= 0) {
    ::dup2(saved_stdout_, STDOUT_FILENO);
    ::close(saved_stdout_);
  }
  if (saved_stderr_ >= 0) {
    ::dup2(saved_stderr_, STDERR_FILENO);
    ::close(saved_stderr_);
  }
}

GmshSession::GmshSession() : threads_(omp_get_max_threads()) {
  try {
    gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::option::setNumber("General.Verbosity", 2);  // errors and warnings only
  } catch (...) {  // no destructor runs for a constructor that throws
    omp_set_num_threads(threads_);
    throw;
  }
}

GmshSession::~GmshSession() {
  try {
    gmsh::finalize();
  } catch (...) {  // never throw from a destructor
  }
  omp_set_num_threads(threads_);
}

}  // namespace flexbody::preprocess::detail
