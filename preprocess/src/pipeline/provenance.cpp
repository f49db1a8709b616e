// Provenance helpers: fbprep's version and the process' memory high-water mark (the input's SHA-256 is
// flexbody::format::sha256_of_file, the seal's implementation).
#include "flexbody/preprocess/fbprep_pipeline.hpp"

#include <sys/resource.h>

namespace flexbody::preprocess {

const char* const kFbprepVersion = FLEXBODY_PACKAGE_VERSION;  // set from project(VERSION) by CMake

double peak_memory_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

}  // namespace flexbody::preprocess
