#pragma once
// flexbody/preprocess/vtu_export.hpp: a body file's mesh and mode shapes as a VTK unstructured grid
// (.vtu, XML, base64-encoded binary arrays) for ParaView.

#include "flexbody/format/body_data.hpp"

#include <filesystem>
#include <string>

namespace flexbody::preprocess {

/// Writes `path` (atomically: a temporary beside it, then rename) with the tetrahedra in the body frame
/// [m] (quadratic ones as VTK quadratic tetrahedra, cell type 24) and, as point data:
/// - per mode, its displacement vector ("mode_01_123.456Hz", M-normalised as stored: [kg^-1/2], scale with
///   Warp By Vector), its nodal stress as a symmetric tensor ("stress_01_123.456Hz", 6 components in ParaView's
///   SymmetricTensor order XX, YY, ZZ, XY, YZ, XZ; nodal_stresses of stress_recovery.hpp with body.material, per
///   unit modal amplitude: [Pa kg^-1/2]) and its von Mises stress ("mises_01", [Pa kg^-1/2]);
/// - the GCMS fields as scalars ("field_001", kg^-1/2);
/// - "interface": 1 + the index of the interface a node belongs to (0: none).
/// Throws std::runtime_error naming the file if it cannot be written, std::invalid_argument if the body's mesh
/// or material cannot give stresses (a body file that read_body_file accepted always can).
void write_body_vtu(const format::BodyData& body, const std::filesystem::path& path);

/// The name write_body_vtu gives mode m (0-based) of frequency f: "mode_01_123.456Hz".
[[nodiscard]] std::string mode_array_name(int m, double frequency_hz);
/// The name of mode m's stress tensor array: mode_array_name with "stress_" for "mode_": "stress_01_123.456Hz".
[[nodiscard]] std::string stress_array_name(int m, double frequency_hz);
/// The name of mode m's von Mises array: "mises_01".
[[nodiscard]] std::string mises_array_name(int m);

}  // namespace flexbody::preprocess
