#include "step_unit.hpp"

#include <fstream>
#include <regex>
#include <sstream>

namespace flexbody::preprocess::detail {

std::optional<LengthUnit> declared_step_unit(const std::filesystem::path& path) {
  // Unit entities may sit anywhere in the DATA section (OpenCASCADE writes them near the end), so the
  // whole file is streamed; only lines that mention units are kept.
  std::ifstream file(path);
  std::ostringstream text;
  std::string line;
  while (std::getline(file, line))
    if (line.find("UNIT") != std::string::npos) text << line << ' ';
  const std::string units = text.str();
  // An inch file declares CONVERSION_BASED_UNIT('INCH', #k) with #k pointing at an SI_UNIT (often mm
  // or m), so the conversion-based unit takes precedence over any SI_UNIT.
  static const std::regex inch(R"(LENGTH_UNIT[^;]*CONVERSION_BASED_UNIT\s*\(\s*'INCH')", std::regex::icase);
  static const std::regex inch_reversed(R"(CONVERSION_BASED_UNIT\s*\(\s*'INCH'[^;]*LENGTH_UNIT)", std::regex::icase);
  if (std::regex_search(units, inch) || std::regex_search(units, inch_reversed)) return LengthUnit::inch;
  static const std::regex si(R"(LENGTH_UNIT[^;]*SI_UNIT\s*\(\s*(\.MILLI\.|\.CENTI\.|\$)\s*,\s*\.METRE\.\s*\))");
  std::smatch match;
  if (std::regex_search(units, match, si)) {
    if (match[1] == ".MILLI.") return LengthUnit::millimetre;
    if (match[1] == ".CENTI.") return LengthUnit::centimetre;
    return LengthUnit::metre;
  }
  return std::nullopt;
}

}  // namespace flexbody::preprocess::detail
