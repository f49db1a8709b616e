#pragma once
// The length unit a STEP file declares in its header (SI_UNIT or CONVERSION_BASED_UNIT).

#include "flexbody/preprocess/length_unit.hpp"

#include <filesystem>
#include <optional>

namespace flexbody::preprocess::detail {

/// The declared length unit of a STEP file, or std::nullopt if none of mm, cm, m, inch is found.
[[nodiscard]] std::optional<LengthUnit> declared_step_unit(const std::filesystem::path& path);

}  // namespace flexbody::preprocess::detail
