// prep_command.cpp: `fbprep INPUT ...`, CAD (STEP, IGES, BREP, .geo) or a tetrahedral .msh -> body file.
#include "cli_common.hpp"

#include "flexbody/preprocess/body_spec.hpp"
#include "flexbody/preprocess/fbprep_pipeline.hpp"
#include "flexbody/preprocess/parallel_session.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>

namespace fp = flexbody::preprocess;

namespace flexbody::cli {

int prep_command(int argc, char** argv) {
  CLI::App app{"fbprep: mesh a part, assemble its mass and stiffness, compute its free-free modes and write a "
               "flexible body file (*.fbh5)."};
  app.get_formatter()->column_width(34);
  app.footer("Other commands:\n  fbprep inspect FILE.fbh5 [--json]   check a body file and print what it holds\n"
             "  fbprep export-vtu FILE.fbh5 -o DIR  mesh, mode shapes, fields, interfaces for ParaView\n"
             "  fbprep list-surfaces INPUT          CAD surface tags, areas, centroids (for body specs)");
  std::string input, output, unit_text, material_text = "steel", solver_text = "auto", mesher_text = "delaunay";
  double mesh_size = 0.0, fmax = 0.0, volume_tolerance = 5e-3, thin_features = 0.0;
  double error_target = preprocess::kDefaultErrorTarget;
  int order = 1, modes = 0;
  bool json = false, quiet = false, geometric_stiffness = false;
  app.add_option("INPUT", input, "STEP/STP, IGES/IGS, BREP, gmsh .geo, gmsh .msh with tetrahedra, or a body spec "
                                 "(.yaml: see docs/fbprep.md; the flags below override it)")->required();
  app.add_option("-o,--output", output, "body file to write (default: INPUT's name with .fbh5, here)");
  app.add_option("--unit", unit_text, "unit of INPUT's coordinates: mm|cm|m|in; overrides the unit a STEP file "
                                      "declares (default: the declared one); required for BREP/.geo/.msh; refused "
                                      "for IGES. --mesh-size and a spec's lengths are in it");
  app.add_option("--mesh-size", mesh_size, "largest element size in the input's unit (default: bounding-box "
                                           "diagonal / 25; a .msh is used as it is)");
  app.add_option("--thin-features", thin_features, "mesh thin features (leads, ribs, walls) with about this many "
                                                   "elements across: each CAD point's size at most its shortest CAD "
                                                   "curve / N (default: off; 1 or 2 where the accuracy estimate warns)");
  app.add_option("--error-target", error_target, "relative error of the first frequency above which the default "
                                                 "mesh is remeshed once where the error estimate puts the error, "
                                                 "aiming at half of it with at most 8 times the tetrahedra (default "
                                                 "0.05; 0: never; not with --mesh-size or --thin-features)");
  app.add_option("--volume-tolerance", volume_tolerance, "how far the mesh's volume may be from the CAD solid's, "
                                                         "relative (default 0.005): the default size is refined "
                                                         "until it holds, a --mesh-size that misses is refused");
  app.add_option("--order", order, "element order: 2 (quadratic tetrahedra, 10 nodes, curved on the CAD surfaces; "
                                  "the default) or 1 (linear, 4 nodes: cheaper, stiffer; see the accuracy estimate); "
                                  "a .msh: by default the order it holds");
  app.add_option("--mesher", mesher_text, "gmsh's 3D algorithm: delaunay (default, reproducible) or hxt (faster; differs per run)");
  app.add_option("--material", material_text, "steel|aluminium|titanium or E=210e9,nu=0.3,rho=7850 (SI)");
  app.add_option("--modes", modes, "number of elastic free-free modes (rigid-body modes never count)");
  app.add_option("--fmax", fmax, "all elastic modes up to this frequency [Hz]; with --modes, --modes caps");
  app.add_option("--eigensolver", solver_text, "auto|arpack|spectra|block-lanczos|slepc (auto: block-lanczos from 50k "
                                               "DOFs, arpack below, slepc under mpirun; slepc: MUMPS and SLEPc, "
                                               "builds with -DFLEXBODY_WITH_SLEPC=ON)");
  app.add_flag("--geometric-stiffness", geometric_stiffness,
               "also the geometric stiffness of the prestress cases (spin, a unit force and moment at each interface), "
               "for rotating and preloaded parts (default: off; a body spec says geometric_stiffness: true)");
  app.add_flag("--json", json, "print the summary as one JSON object on stdout instead of the report");
  app.add_flag("-q,--quiet", quiet, "no progress and no report (errors still go to stderr)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail(std::string(e.what()) + " (see fbprep --help)", kBadCommandLine);
  }

  // Option values: a bad one is a bad command line (exit 2). A body spec (.yaml) gives the defaults;
  // flags given on the command line override it.
  fp::PrepOptions options;
  const auto start = std::chrono::steady_clock::now();
  const bool from_spec = fp::is_body_spec(input);
  auto given = [&app](const char* name) { return app.count(name) > 0; };
  auto record = [&options](const std::string& name, const std::string& value) {
    fp::record_option(options, name, value);
  };
  try {
    if (from_spec) {
      options = fp::read_body_spec(input);
    } else {
      options.input = input;
      options.modes.modes = 10;
      record("input", input);
    }
    const std::filesystem::path stem_source = from_spec ? std::filesystem::path(input) : options.input;
    options.output = output.empty() ? stem_source.filename().replace_extension(".fbh5") : std::filesystem::path(output);
    record("output", options.output.string());
    if (!from_spec || given("--unit")) {
      if (!unit_text.empty()) {
        const std::optional<fp::LengthUnit> spec_unit = options.mesh.unit;
        options.mesh.unit = fp::length_unit_from_string(unit_text);
        if (!options.mesh.unit) throw std::invalid_argument("--unit '" + unit_text + "' is not one of mm, cm, m, in");
        // Like every flag, --unit replaces the spec's value; the spec's lengths are then read in it too.
        options.mesh.unit_source = "--unit " + unit_text;
        if (spec_unit && *spec_unit != *options.mesh.unit)
          options.mesh.unit_source += fmt::format(" (replacing the body spec's unit: {})", fp::to_string(*spec_unit));
      }
      record("unit", unit_text.empty() ? "(from file)" : unit_text);
    }
    // A value given is used as given: 0 is not "the default" (leave the flag out for that).
    if (given("--mesh-size") && !(std::isfinite(mesh_size) && mesh_size > 0.0))
      throw std::invalid_argument(fmt::format("--mesh-size must be a positive number (the largest element size in the "
                                              "input's unit; leave it out for the default), got {}", mesh_size));
    if (given("--modes") && modes < 1)
      throw std::invalid_argument(fmt::format("--modes must be at least 1, got {}", modes));
    if (given("--fmax") && !(std::isfinite(fmax) && fmax > 0.0))
      throw std::invalid_argument(fmt::format("--fmax must be a positive frequency in Hz, got {}", fmax));
    if (given("--order") && order != 1 && order != 2)
      throw std::invalid_argument(fmt::format("--order {}: the element order is 1 (linear tetrahedra) or 2 (quadratic, "
                                              "10 nodes)", order));
    if (!from_spec || given("--mesh-size")) {
      options.mesh.mesh_size = mesh_size;
      record("mesh_size", fmt::format("{}", mesh_size));
    }
    if (given("--thin-features")) {
      if (!(std::isfinite(thin_features) && thin_features > 0.0))
        throw std::invalid_argument(fmt::format("--thin-features must be a positive number of elements across a thin "
                                                "feature (leave it out for none), got {}", thin_features));
      options.mesh.thin_feature_elements = thin_features;
      record("thin_features", fmt::format("{}", thin_features));
    }
    if (given("--error-target")) {
      if (!(std::isfinite(error_target) && error_target >= 0.0 && error_target < 1.0))
        throw std::invalid_argument(fmt::format("--error-target must be a relative frequency error in [0, 1) (0.05: "
                                                "5 %; 0: no refinement), got {}", error_target));
      options.error_target = error_target;
      record("error_target", fmt::format("{}", error_target));
    }
    if (given("--volume-tolerance") && !(std::isfinite(volume_tolerance) && volume_tolerance > 0.0 && volume_tolerance < 1.0))
      throw std::invalid_argument(fmt::format("--volume-tolerance must be a fraction of the CAD volume between 0 and 1 "
                                              "(0.005: 0.5 %), got {}", volume_tolerance));
    if (!from_spec || given("--volume-tolerance")) options.mesh.volume_tolerance = volume_tolerance;
    record("volume_tolerance", fmt::format("{}", options.mesh.volume_tolerance));
    if (given("--order")) options.mesh.order = order;  // like every flag, it replaces the spec's
    record("element_order", options.mesh.order ? std::to_string(*options.mesh.order) : std::string("default"));
    if (!from_spec || given("--mesher")) {
      const std::optional<fp::MeshAlgorithm> mesher = fp::mesh_algorithm_from_string(mesher_text);
      if (!mesher) throw std::invalid_argument("--mesher '" + mesher_text + "' is not one of delaunay, hxt");
      options.mesh.algorithm = *mesher;
    }
    record("mesher", std::string(fp::to_string(options.mesh.algorithm)));
    if (!from_spec || given("--material")) {
      options.material = fp::parse_material(material_text);
      record("material", material_text);
    }
    if (given("--modes") || given("--fmax")) {  // either flag replaces the spec's whole mode request
      options.modes.modes = modes;  // 0 with --fmax alone: every mode up to fmax
      options.modes.fmax_hz = fmax;
    }
    record("modes", std::to_string(options.modes.modes));
    record("fmax", fmt::format("{}", options.modes.fmax_hz));
    if (given("--geometric-stiffness")) options.geometric_stiffness = true;  // like every flag, over the spec's
    record("geometric_stiffness", options.geometric_stiffness ? "true" : "false");
    if (!from_spec || given("--eigensolver")) {
      options.modes.solver.backend = fp::eigensolver_backend_from_string(solver_text);
      record("eigensolver", solver_text);
    }
    fp::record_resolved_options(options);  // what flags did not record: the same values, where they are (Python's prep)
    if (fp::parallel_ranks() > 1 && options.modes.solver.backend == fp::EigensolverBackend::automatic &&
        fp::slepc_available())  // the one backend that uses the ranks
      options.modes.solver.backend = fp::EigensolverBackend::slepc;
    if (fp::parallel_ranks() > 1 && options.modes.solver.backend != fp::EigensolverBackend::slepc)
      throw std::invalid_argument(fmt::format("--eigensolver {} runs on one process, but fbprep was started on {} MPI "
                                              "ranks: use --eigensolver slepc under mpirun",
                                              fp::to_string(options.modes.solver.backend), fp::parallel_ranks()));
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
    if (!quiet)  // on stderr whatever it is, and beside --json's stdout
      options.mesh.warning = [](const std::string& message) { std::fprintf(stderr, "fbprep: warning: %s\n", message.c_str()); };
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

}  // namespace flexbody::cli
