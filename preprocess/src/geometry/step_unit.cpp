#include "step_unit.hpp"

#include <fstream>
#include <regex>
#include <sstream>

namespace flexbody::preprocess::detail {

StepLengthUnit declared_step_unit(const std::filesystem::path& path) {
  // Unit entities may sit anywhere in the DATA section (OpenCASCADE writes them near the end), so the
  // whole file is streamed; only the statements (up to ';', possibly over several lines) that mention
  // units are kept.
  std::ifstream file(path);
  std::ostringstream text;
  std::string line, statement;
  while (std::getline(file, line)) {
    for (std::size_t begin = 0; begin <= line.size();) {
      const std::size_t end = line.find(';', begin);
      statement.append(line, begin, end == std::string::npos ? std::string::npos : end - begin);
      if (end == std::string::npos) break;
      if (statement.find("UNIT") != std::string::npos) text << statement << "; ";
      statement.clear();
      begin = end + 1;
    }
    statement += ' ';
  }
  const std::string units = text.str();
  static const std::regex length_unit(R"(LENGTH_UNIT\s*\(\s*\))", std::regex::icase);
  if (!std::regex_search(units, length_unit)) return {false, std::nullopt};
  // An inch file declares CONVERSION_BASED_UNIT('INCH', #k) with #k pointing at an SI_UNIT (often mm
  // or m), so the conversion-based unit takes precedence over any SI_UNIT.
  static const std::regex inch(R"(LENGTH_UNIT[^;]*CONVERSION_BASED_UNIT\s*\(\s*'INCH')", std::regex::icase);
  static const std::regex inch_reversed(R"(CONVERSION_BASED_UNIT\s*\(\s*'INCH'[^;]*LENGTH_UNIT)", std::regex::icase);
  if (std::regex_search(units, inch) || std::regex_search(units, inch_reversed)) return {true, LengthUnit::inch};
  static const std::regex si(R"(LENGTH_UNIT[^;]*SI_UNIT\s*\(\s*(\.MILLI\.|\.CENTI\.|\$)\s*,\s*\.METRE\.\s*\))");
  std::smatch match;
  if (std::regex_search(units, match, si)) {
    if (match[1] == ".MILLI.") return {true, LengthUnit::millimetre};
    if (match[1] == ".CENTI.") return {true, LengthUnit::centimetre};
    return {true, LengthUnit::metre};
  }
  return {true, std::nullopt};
}

}  // namespace flexbody::preprocess::detail
