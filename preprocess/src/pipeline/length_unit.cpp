#include "flexbody/preprocess/length_unit.hpp"

namespace flexbody::preprocess {

std::string_view to_string(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::millimetre: return "mm";
    case LengthUnit::centimetre: return "cm";
    case LengthUnit::metre: return "m";
    case LengthUnit::inch: return "in";
  }
  return "?";
}

std::optional<LengthUnit> length_unit_from_string(std::string_view text) {
  if (text == "mm") return LengthUnit::millimetre;
  if (text == "cm") return LengthUnit::centimetre;
  if (text == "m") return LengthUnit::metre;
  if (text == "in") return LengthUnit::inch;
  return std::nullopt;
}

double metres_per(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::millimetre: return 1e-3;
    case LengthUnit::centimetre: return 1e-2;
    case LengthUnit::metre: return 1.0;
    case LengthUnit::inch: return 0.0254;
  }
  return 1.0;
}

}  // namespace flexbody::preprocess
