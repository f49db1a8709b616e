#pragma once
// flexbody/preprocess/body_summary.hpp: what a body file holds, for `fbprep inspect`.

#include "flexbody/format/body_data.hpp"

#include <filesystem>
#include <string>

namespace flexbody::preprocess {

/// A readable summary: provenance, material, mass, mesh, modes and the GCMS constants, including the
/// range of the reduced stiffness spectrum sqrt(eig(K̂)) / 2π (the fields' own frequencies with G_ff = I;
/// its top is what an explicit integrator's step would have to resolve, formulations.md, "The Method": the fields'
/// spectrum).
[[nodiscard]] std::string body_report(const format::BodyData& body, const std::filesystem::path& file);

/// The same as one JSON object (a single line).
[[nodiscard]] std::string body_json(const format::BodyData& body, const std::filesystem::path& file);

}  // namespace flexbody::preprocess
