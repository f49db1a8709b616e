#pragma once
// flexbody/preprocess/length_unit.hpp: the length units an input may be given in.

#include <optional>
#include <string>
#include <string_view>

namespace flexbody::preprocess {

enum class LengthUnit { millimetre, centimetre, metre, inch };

/// "mm", "cm", "m", "in".
[[nodiscard]] std::string_view to_string(LengthUnit unit);
/// Parses "mm", "cm", "m", "in"; std::nullopt for anything else.
[[nodiscard]] std::optional<LengthUnit> length_unit_from_string(std::string_view text);
/// Metres per one `unit` (1e-3 for mm, 0.0254 for in).
[[nodiscard]] double metres_per(LengthUnit unit);

}  // namespace flexbody::preprocess
