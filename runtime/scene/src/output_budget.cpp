#include "flexbody/scene/output_budget.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <utility>

namespace flexbody::scene {

double OutputEstimate::bytes() const {
  double sum = 0.0;
  for (const OutputPart& p : parts) sum += p.bytes;
  return sum;
}

double OutputEstimate::files() const {
  double sum = 0.0;
  for (const OutputPart& p : parts) sum += p.files;
  return sum;
}

std::string format_size(double bytes) {
  static constexpr const char* kUnits[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  std::size_t unit = 0;
  while (bytes >= 999.5 && unit + 1 < std::size(kUnits)) {
    bytes /= 1000.0;
    ++unit;
  }
  return fmt::format("{:.3g} {}", bytes, kUnits[unit]);
}

double parse_size(const std::string& text) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double number = std::strtod(begin, &end);
  std::string unit(end);
  unit.erase(std::remove_if(unit.begin(), unit.end(), [](unsigned char c) { return std::isspace(c) != 0; }), unit.end());
  static const std::pair<const char*, double> kUnits[] = {
      {"", 1.0},     {"B", 1.0},    {"kB", 1e3},   {"KB", 1e3},   {"MB", 1e6},   {"GB", 1e9},   {"TB", 1e12},
      {"KiB", 1024.0}, {"MiB", 1048576.0}, {"GiB", 1073741824.0}, {"TiB", 1099511627776.0}};
  for (const auto& [name, factor] : kUnits)
    if (end != begin && errno != ERANGE && unit == name && std::isfinite(number) && number > 0.0) return number * factor;
  throw std::invalid_argument(fmt::format("'{}' is not a size: a positive number of bytes, or with a unit: kB, MB, GB, "
                                          "TB (powers of 1000), KiB, MiB, GiB, TiB", text));
}

void check_output_budget(const OutputEstimate& estimate, const OutputBudget& budget, const std::string& step_where) {
  const double bytes = estimate.bytes(), files = estimate.files();
  if (bytes <= budget.bytes && files <= budget.files) return;
  // The part that most exceeds its share names the lines to change.
  const bool by_files = files / budget.files > bytes / budget.bytes;
  const auto largest = std::max_element(estimate.parts.begin(), estimate.parts.end(), [by_files](const OutputPart& a,
                                                                                                  const OutputPart& b) {
    return by_files ? a.files < b.files : a.bytes < b.bytes;
  });
  throw OutputBudgetError(fmt::format(
      "{}: {}: {:.0f} {} ({} in {:.0f} files; the step is set at {}): the run would write about {} in {:.0f} files, "
      "over the output budget of {} and {:.0f} files (write less often, or raise it: {})",
      largest->where, largest->what, largest->rows, largest->what.rfind("paraview", 0) == 0 ? "frames" : "rows each",
      format_size(largest->bytes), largest->files, step_where, format_size(bytes), files, format_size(budget.bytes),
      budget.files,
      by_files ? "the scene's output_budget: {files: N}" : "fbsim --max-output SIZE or the scene's output_budget: {size: SIZE}"));
}

}  // namespace flexbody::scene
