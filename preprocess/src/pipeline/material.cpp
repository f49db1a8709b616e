#include "flexbody/preprocess/material.hpp"

#include <cmath>
#include <charconv>
#include <map>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace flexbody::preprocess {
namespace {

// Room-temperature handbook values (structural steel, 6061-class aluminium, Ti-6Al-4V).
const std::map<std::string, Material, std::less<>>& named_materials() {
  static const std::map<std::string, Material, std::less<>> materials = {
      {"steel", {"steel", 210e9, 0.30, 7850.0}},
      {"aluminium", {"aluminium", 70e9, 0.33, 2700.0}},
      {"aluminum", {"aluminium", 70e9, 0.33, 2700.0}},
      {"titanium", {"titanium", 114e9, 0.34, 4430.0}},
  };
  return materials;
}

double parse_number(std::string_view key, std::string_view value) {
  std::string text(value);
  std::size_t used = 0;
  double number = 0.0;
  try {
    number = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size())
    throw std::invalid_argument("material: " + std::string(key) + "='" + text + "' is not a number");
  return number;
}

}  // namespace

Material parse_material(std::string_view text) {
  if (auto it = named_materials().find(text); it != named_materials().end()) return it->second;
  if (text.find('=') == std::string_view::npos)
    throw std::invalid_argument("material: '" + std::string(text) +
                                "' is unknown; use steel, aluminium, titanium or E=...,nu=...,rho=...");
  Material material{"custom", 0.0, 0.0, 0.0};
  std::map<std::string, double*, std::less<>> fields = {
      {"E", &material.youngs_modulus}, {"nu", &material.poisson_ratio}, {"rho", &material.density}};
  std::map<std::string, bool, std::less<>> given;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    std::size_t end = text.find(',', begin);
    if (end == std::string_view::npos) end = text.size();
    std::string_view item = text.substr(begin, end - begin);
    std::size_t eq = item.find('=');
    if (eq == std::string_view::npos)
      throw std::invalid_argument("material: '" + std::string(item) + "' is not KEY=VALUE");
    std::string_view key = item.substr(0, eq);
    const auto field = fields.find(key);
    if (field == fields.end())
      throw std::invalid_argument("material: unknown key '" + std::string(key) + "'; keys are E, nu, rho");
    if (given[field->first])
      throw std::invalid_argument("material: " + field->first + " is given twice");
    *field->second = parse_number(key, item.substr(eq + 1));
    given[field->first] = true;
    begin = end + 1;
  }
  for (const auto& [key, value] : fields)
    if (!given[key]) throw std::invalid_argument("material: " + key + " is missing");
  check_material(material);
  return material;
}

void check_material(const Material& m) {
  auto show = [](double v) { return fmt::format("{}", v); };
  if (!std::isfinite(m.youngs_modulus) || m.youngs_modulus <= 0.0)
    throw std::invalid_argument("material: E must be positive, got " + show(m.youngs_modulus));
  if (!std::isfinite(m.density) || m.density <= 0.0)
    throw std::invalid_argument("material: rho must be positive, got " + show(m.density));
  if (!std::isfinite(m.poisson_ratio) || m.poisson_ratio <= -1.0 || m.poisson_ratio >= 0.5)
    throw std::invalid_argument("material: nu must lie in (-1, 0.5), got " + show(m.poisson_ratio));
}

double lame_lambda(const Material& m) {
  const double nu = m.poisson_ratio;
  return m.youngs_modulus * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
}

double shear_modulus(const Material& m) { return m.youngs_modulus / (2.0 * (1.0 + m.poisson_ratio)); }

}  // namespace flexbody::preprocess
