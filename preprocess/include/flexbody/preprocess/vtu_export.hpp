#pragma once
// flexbody/preprocess/vtu_export.hpp: a body file's mesh and mode shapes as a VTK unstructured grid
// (.vtu, XML, base64-encoded binary arrays) for ParaView.

#include "flexbody/format/body_data.hpp"

#include <filesystem>
#include <string>

namespace flexbody::preprocess {

/// Writes `path` (atomically: a temporary beside it, then rename) with the tetrahedra in the body frame
/// [m] and, as point data, one displacement vector per mode ("mode_01_123.456Hz", M-normalised as
/// stored: [kg^-1/2], scale with Warp By Vector), the GCMS fields as scalars ("field_001", kg^-1/2) and
/// "interface": 1 + the index of the interface a node belongs to (0: none). Throws std::runtime_error
/// naming the file if it cannot be written.
void write_body_vtu(const format::BodyData& body, const std::filesystem::path& path);

/// The name write_body_vtu gives mode m (0-based) of frequency f: "mode_01_123.456Hz".
[[nodiscard]] std::string mode_array_name(int m, double frequency_hz);

}  // namespace flexbody::preprocess
