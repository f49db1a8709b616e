#include "step_unit.hpp"

#include <fstream>
#include <regex>
#include <sstream>

namespace flexbody::preprocess::detail {

std::optional<LengthUnit> declared_step_unit(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::string line;
  // The unit entities sit in the first part of the DATA section; read a bounded prefix.
  std::ostringstream text;
  std::size_t read = 0;
  while (read < (8u << 20) && std::getline(file, line)) {
    if (line.find("LENGTH_UNIT") != std::string::npos || line.find("SI_UNIT") != std::string::npos ||
        line.find("CONVERSION_BASED_UNIT") != std::string::npos)
      text << line << ' ';
    read += line.size();
  }
  const std::string units = text.str();
  static const std::regex si(R"(SI_UNIT\s*\(\s*(\.MILLI\.|\.CENTI\.|\$)\s*,\s*\.METRE\.\s*\))");
  static const std::regex inch(R"(CONVERSION_BASED_UNIT\s*\(\s*'INCH')", std::regex::icase);
  std::smatch match;
  if (std::regex_search(units, match, si)) {
    if (match[1] == ".MILLI.") return LengthUnit::millimetre;
    if (match[1] == ".CENTI.") return LengthUnit::centimetre;
    return LengthUnit::metre;
  }
  if (std::regex_search(units, inch)) return LengthUnit::inch;
  return std::nullopt;
}

}  // namespace flexbody::preprocess::detail
