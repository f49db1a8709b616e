#pragma once
// What fbprep_cli_test.cpp and fbprep_cli_input_test.cpp share: running fbprep, the sample inputs, the checks of
// a refusal (one line on stderr, a non-zero exit, nothing under the output name).
#include "cli_run.hpp"
#include "vtu_read.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

namespace fbprep_cli {

using flexbody::test::CliRun;
using flexbody::test::slurp;
using flexbody::test::base64_decode;
using flexbody::test::vtu_array;

inline CliRun fbprep(const std::filesystem::path& dir, const std::string& arguments) {
  return flexbody::test::run_fbprep(dir, arguments);
}

// The tests below mesh it at 6 mm for speed: that mesh holds 100.7 % of the CAD solid's volume, beyond fbprep's
// default 0.5 % (issue 28), so they pass --volume-tolerance 0.01.
inline std::filesystem::path bracket_step() {
  return std::filesystem::path(FLEXBODY_SOURCE_DIR) / "meshes" / "bracket.step";
}
// A 1 x 0.05 x 0.05 box meant in metres, written by gmsh, whose STEP writer declares mm.
inline std::filesystem::path gmsh_beam_step() {
  return std::filesystem::path(FLEXBODY_TEST_DATA_DIR) / "gmsh-beam" / "beam_1m.step";
}

// Only the files the test itself wrote remain in `dir` (no body file, no temporary).
inline void expect_no_output(const std::filesystem::path& dir) {
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "stdout.txt" || name == "stderr.txt" || name.rfind("input", 0) == 0)
        << "left behind: " << name;
  }
}

inline void expect_refusal(const std::filesystem::path& dir, const std::string& arguments, const std::string& message) {
  SCOPED_TRACE(arguments);
  const CliRun run = fbprep(dir, arguments + " -o out.fbh5");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  EXPECT_EQ(run.err.rfind("fbprep: error: ", 0), 0u) << run.err;
  EXPECT_NE(run.err.find(message), std::string::npos) << run.err;
  expect_no_output(dir);
}

inline void write(const std::filesystem::path& path, const std::string& text) { flexbody::test::write_text(path, text); }

constexpr const char* kOcc = "SetFactory(\"OpenCASCADE\");\n";

}  // namespace fbprep_cli
