#pragma once
// What the fbsim command-line tests share (fbsim_cli_test.cpp, fbsim_cli_output_test.cpp, fbsim_cli_run_test.cpp): the
// bar made by fbprep, the issue's scene, the check of a refused scene, and the CSV outputs read back.
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fbsim_cli {

using flexbody::test::CliRun;
using flexbody::test::run_fbprep;
using flexbody::test::run_fbsim;
using flexbody::test::write_text;

// A 1 x 0.05 x 0.05 m steel bar with rbe3 interfaces root (x = 0) and tip (x = 1), 8 modes.
inline const std::filesystem::path& bar_folder() {
  static const std::filesystem::path dir = [] {
    const auto d = flexbody::test::scratch_dir();
    write_text(d / "bar.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 0.05, 0.05};\n");
    write_text(d / "bar.yaml", R"(input: bar.geo
unit: m
mesh: {size: 0.025}
reduction: {modes: 8}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}}
  tip: {select: {plane: {point: [1, 0, 0], normal: [1, 0, 0]}}}
)");
    const CliRun prep = run_fbprep(d, "bar.yaml -o bar.fbh5 -q");
    EXPECT_EQ(prep.exit_code, 0) << prep.err;
    return d;
  }();
  return dir;
}

inline const char* kIssueScene = R"(bodies:
  bar: {file: bar.fbh5, modes: 8}
joints:
  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}
gravity: [0, -9.81, 0]
integrator: {type: generalized-alpha, rho_inf: 0.9, step: 1.0e-4, end: 2.0}
outputs:
  tip: {body: bar, interface: tip, quantities: [position]}
)";

inline void expect_scene_error(const std::string& scene, int line, const std::string& message) {
  SCOPED_TRACE(scene);
  const auto& dir = bar_folder();
  write_text(dir / "bad.yaml", scene);
  const CliRun run = run_fbsim(dir, "bad.yaml -o bad_out -q");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("fbsim: error: bad.yaml:" + std::to_string(line) + ": " + message), std::string::npos) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
}

inline std::vector<std::vector<double>> csv_numbers(const std::filesystem::path& file) {
  return flexbody::test::read_csv_numbers(file);
}

// The t column of an output file.
inline std::vector<double> times_of(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // the header
  std::vector<double> times;
  while (std::getline(in, line)) times.push_back(std::stod(line.substr(0, line.find(','))));
  return times;
}

}  // namespace fbsim_cli
