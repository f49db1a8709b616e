#pragma once
// flexbody/preprocess/body_spec.hpp: the body spec, a YAML file that says what a scene needs from one
// part, kept beside the CAD and rerun with `fbprep body.yaml -o body.fbh5`:
//
//   input: beam.step                # relative paths are relative to the spec
//   unit: m                         # unit of the input's coordinates (wins over what a STEP file
//                                   # declares) and of every length below
//   material: {E: 210e9, nu: 0.3, rho: 7850}      # or: steel | aluminium | titanium
//   mesh: {size: 0.0125, order: 1}  # order: 2 (quadratic tetrahedra, the default) or 1 (linear)
//   reduction: {kind: free-free, modes: 8, fmax: 2000, eigensolver: arpack}
//   interfaces:
//     root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0], tolerance: 1e-6}}, coupling: rbe3}
//     bore: {select: {cylinder: {point: [0.045, 0.02, 0], direction: [0, 0, 1], radius: 0.005}}}
//     tip:  {select: {box: {min: [0.99, -1, -1], max: [1.01, 1, 1]}}}
//     seat: {select: {surfaces: [7, 8]}}     # CAD surface tags (fbprep list-surfaces)
//     flange: {select: {group: flange}}      # a gmsh physical group of surfaces (.geo, .msh)
//   load_points:                     # rbe3 interfaces that also get static correction modes
//     hook: {select: {cylinder: {...}}, loads: [fx, fy, mz]}   # default: all of fx fy fz mx my mz
//   output_regions:                  # stress recovery; absent: the whole body if small; {}: none
//     fillet: {select: {box: {min: [...], max: [...]}}}        # the selected surface's nodes
//     body: {select: all}                                       # every node

#include "flexbody/preprocess/fbprep_pipeline.hpp"

#include <filesystem>
#include <string>

namespace YAML {
class Node;
}

namespace flexbody::preprocess {

/// True for a .yaml or .yml file name.
[[nodiscard]] bool is_body_spec(const std::filesystem::path& path);

/// Reads a body spec into fbprep options (input, unit, material, mesh, reduction, interfaces, load points,
/// output regions; output and progress are left to the caller) and records every value in
/// `recorded_options`. Throws std::invalid_argument "<spec>:<line>: <problem>" for a missing or unreadable
/// file, YAML syntax errors, unknown or repeated keys or names, wrong types, non-finite numbers and values
/// out of range, each naming its line.
[[nodiscard]] PrepOptions read_body_spec(const std::filesystem::path& spec);

/// The same from a body spec's document `root` (one built in code: the Python package's prep), whose errors begin
/// with `source`; its relative input path is relative to `base`.
[[nodiscard]] PrepOptions read_body_spec(const YAML::Node& root, const std::string& source,
                                         const std::filesystem::path& base);

/// Sets option `name`'s recorded value (PrepOptions::recorded_options, the body file's provenance), in its place if
/// recorded before, else at the end.
void record_option(PrepOptions& options, const std::string& name, const std::string& value);
/// Records what a run uses that a spec need not say: the output, volume tolerance, element order, mesher, modes,
/// fmax and geometric stiffness (fbprep records them for every run, from a spec or from flags).
void record_resolved_options(PrepOptions& options);

}  // namespace flexbody::preprocess
