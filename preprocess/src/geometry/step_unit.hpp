#pragma once
// The length unit a STEP file declares in its header (SI_UNIT or CONVERSION_BASED_UNIT).

#include "flexbody/preprocess/length_unit.hpp"

#include <filesystem>
#include <optional>

namespace flexbody::preprocess::detail {

/// What a STEP file says about its length unit.
struct StepLengthUnit {
  /// The file has a LENGTH_UNIT entity at all. Without one OpenCASCADE takes its numbers as mm.
  bool declared = false;
  /// The declared unit when it is mm, cm, m or inch; std::nullopt when none is declared or it is
  /// another one (OpenCASCADE still converts those to mm, by a factor fbprep does not know).
  std::optional<LengthUnit> unit;
};

/// The declared length unit of a STEP file.
[[nodiscard]] StepLengthUnit declared_step_unit(const std::filesystem::path& path);

}  // namespace flexbody::preprocess::detail
