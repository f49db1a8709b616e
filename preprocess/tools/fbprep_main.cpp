// fbprep: CAD (STEP, IGES, BREP, .geo) or a tetrahedral .msh -> flexible body file (*.fbh5).
//
//   fbprep part.step -o part.fbh5 --material steel --modes 12
//
// Errors: one line on stderr and no file under the output name. Exit code 2 when the command line asks
// for something impossible (an unknown option, a bad value, a request the part cannot meet: library
// functions signal these with std::invalid_argument), 1 when reading the input or computing fails.
#include "flexbody/preprocess/fbprep_pipeline.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>

namespace fp = flexbody::preprocess;

namespace {

// One line on stderr, whatever the message holds (gmsh and OpenCASCADE messages may span lines).
int fail(std::string message, int code) {
  std::replace(message.begin(), message.end(), '\n', ' ');
  std::fflush(stdout);
  std::fprintf(stderr, "fbprep: error: %s\n", message.c_str());
  return code;
}

constexpr int kBadCommandLine = 2;
constexpr int kFailed = 1;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fbprep: mesh a part, assemble its mass and stiffness, compute its free-free modes and write a "
               "flexible body file (*.fbh5)."};
  app.get_formatter()->column_width(34);
  std::string input, output, unit_text, material_text = "steel", solver_text = "arpack";
  double mesh_size = 0.0, fmax = 0.0;
  int order = 1, modes = 0;
  bool json = false, quiet = false;
  app.add_option("INPUT", input, "STEP/STP, IGES/IGS, BREP, gmsh .geo, or gmsh .msh with tetrahedra")->required();
  app.add_option("-o,--output", output, "body file to write (default: INPUT's name with .fbh5, here)");
  app.add_option("--unit", unit_text, "length unit of INPUT: mm|cm|m|in (required for BREP/.geo/.msh; STEP and "
                                      "IGES declare their own: then only the unit of --mesh-size, default the "
                                      "STEP's declared unit, mm for IGES)");
  app.add_option("--mesh-size", mesh_size, "largest element size in --unit (default: bounding-box diagonal / 25; "
                                           "a .msh is used as it is)");
  app.add_option("--order", order, "element order: 1 (linear tetrahedra)");
  app.add_option("--material", material_text, "steel|aluminium|titanium or E=210e9,nu=0.3,rho=7850 (SI)");
  app.add_option("--modes", modes, "number of elastic free-free modes (rigid-body modes never count)");
  app.add_option("--fmax", fmax, "all elastic modes up to this frequency [Hz]; with --modes, --modes caps");
  app.add_option("--eigensolver", solver_text, "arpack|spectra");
  app.add_flag("--json", json, "print the summary as one JSON object on stdout instead of the report");
  app.add_flag("-q,--quiet", quiet, "no progress and no report (errors still go to stderr)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail(std::string(e.what()) + " (see fbprep --help)", kBadCommandLine);
  }

  // Option values: a bad one is a bad command line (exit 2).
  fp::PrepOptions options;
  const auto start = std::chrono::steady_clock::now();
  try {
    options.input = input;
    options.output = output.empty() ? std::filesystem::path(input).filename().replace_extension(".fbh5")
                                    : std::filesystem::path(output);
    if (!unit_text.empty()) {
      options.mesh.unit = fp::length_unit_from_string(unit_text);
      if (!options.mesh.unit) throw std::invalid_argument("--unit '" + unit_text + "' is not one of mm, cm, m, in");
    }
    if (!(mesh_size >= 0.0)) throw std::invalid_argument(fmt::format("--mesh-size must be positive, got {}", mesh_size));
    if (modes < 0) throw std::invalid_argument(fmt::format("--modes must be positive, got {}", modes));
    if (!(fmax >= 0.0)) throw std::invalid_argument(fmt::format("--fmax must be positive, got {}", fmax));
    if (order != 1)
      throw std::invalid_argument(fmt::format("--order {}: only linear tetrahedra (--order 1) are implemented", order));
    options.mesh.mesh_size = mesh_size;
    options.mesh.order = order;
    options.material = fp::parse_material(material_text);
    options.modes.modes = (modes == 0 && fmax == 0.0) ? 10 : modes;
    options.modes.fmax_hz = fmax;
    options.modes.solver.backend = fp::eigensolver_backend_from_string(solver_text);
    options.recorded_options = {{"input", input},
                                {"output", options.output.string()},
                                {"unit", unit_text.empty() ? "(from file)" : unit_text},
                                {"mesh_size", fmt::format("{}", mesh_size)},
                                {"element_order", std::to_string(order)},
                                {"material", material_text},
                                {"modes", std::to_string(options.modes.modes)},
                                {"fmax", fmt::format("{}", fmax)},
                                {"eigensolver", solver_text}};
  } catch (const std::exception& e) {
    return fail(e.what(), kBadCommandLine);
  }

  try {
    if (!quiet && !json && ::isatty(STDERR_FILENO)) {
      options.progress = [start](const std::string& message) {
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::fprintf(stderr, "[%7.2f s] %s\n", t, message.c_str());
      };
    }
    const fp::PrepSummary summary = fp::run_fbprep(options);
    if (json) std::cout << summary.json() << '\n';
    else if (!quiet) std::cout << summary.full_report();
  } catch (const std::invalid_argument& e) {
    return fail(e.what(), kBadCommandLine);
  } catch (const std::exception& e) {
    return fail(e.what(), kFailed);
  } catch (...) {  // a library throwing something that is not a std::exception
    return fail("internal error: unexpected exception type", kFailed);
  }
  return 0;
}
