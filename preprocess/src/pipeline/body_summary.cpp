#include "flexbody/preprocess/body_summary.hpp"

#include "../modes/frequency.hpp"
#include "report_text.hpp"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string_view>
#include <utility>

namespace flexbody::preprocess {
namespace {

using detail::vector3;

// Lowest and highest sqrt(λ)/2π of K̂ (λ clipped at 0: K̂ is positive semi-definite up to round-off).
std::pair<double, double> stiffness_frequency_range(const Eigen::MatrixXd& k_hat) {
  if (k_hat.size() == 0) return {0.0, 0.0};
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(k_hat, Eigen::EigenvaluesOnly).eigenvalues();
  auto hz = [](double l) { return std::sqrt(std::max(l, 0.0)) / kTwoPi; };
  return {hz(lambda(0)), hz(lambda(lambda.size() - 1))};
}

std::uintmax_t file_bytes(const std::filesystem::path& file) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(file, error);
  return error ? 0 : size;
}

// Strings come from the file, which anyone may have written: in the report each is shown with its control
// characters escaped (C0, DEL and C1 as \xHH or \u00HH, bytes that are not UTF-8 as \xHH, a backslash doubled) and
// cut after kShownBytes of the file's bytes; --json escapes by itself and takes the cut only.
constexpr std::size_t kShownBytes = 200;
constexpr std::size_t kShownOptions = 100;

// The length of the valid UTF-8 sequence at text[i] and its code point; 0 when it is not one.
std::pair<std::size_t, char32_t> utf8_at(std::string_view text, std::size_t i) {
  const auto byte = [&text](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  const std::size_t length = lead >= 0xC2 && lead <= 0xDF ? 2 : lead >= 0xE0 && lead <= 0xEF ? 3
                           : lead >= 0xF0 && lead <= 0xF4 ? 4 : 0;
  if (length == 0 || i + length > text.size()) return {0, 0};
  char32_t code = lead & (0x7F >> length);
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return {0, 0};
    code = (code << 6) | (byte(i + k) & 0x3F);
  }
  const bool shortest = length == 2 || (length == 3 && code >= 0x800) || (length == 4 && code >= 0x10000);
  if (!shortest || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return {0, 0};
  return {length, code};
}

// The first kShownBytes bytes of `text` (not splitting a UTF-8 sequence), then "... (N bytes)" if it is longer.
std::size_t shown_length(std::string_view text) {
  if (text.size() <= kShownBytes) return text.size();
  std::size_t end = kShownBytes;
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) --end;
  return end;
}
std::string cut_note(std::string_view text) {
  return text.size() > kShownBytes ? fmt::format("... ({} bytes)", text.size()) : std::string();
}

std::string printable(std::string_view text) {
  const std::size_t end = shown_length(text);
  std::string out;
  for (std::size_t i = 0; i < end;) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7F) {
      out += fmt::format("\\x{:02x}", c);
      ++i;
    } else if (c == '\\') {
      out += "\\\\";
      ++i;
    } else if (c < 0x80) {
      out += static_cast<char>(c);
      ++i;
    } else if (const auto [length, code] = utf8_at(text, i); length == 0 || i + length > end) {
      out += fmt::format("\\x{:02x}", c);
      ++i;
    } else if (code <= 0x9F) {  // C1 controls (U+0080 to U+009F), e.g. U+009B, a terminal's CSI
      out += fmt::format("\\u{:04x}", static_cast<unsigned>(code));
      i += length;
    } else {
      out.append(text.substr(i, length));
      i += length;
    }
  }
  return out + cut_note(text);
}

std::string capped(std::string_view text) {  // for --json: nlohmann escapes, only the length is cut
  return std::string(text.substr(0, shown_length(text))) + cut_note(text);
}

nlohmann::ordered_json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
}

// Mode 1's stiffening under a spin Ω about each body axis (geometric_stiffness.hpp): its ω² grows by S Ω² with
// S = Σ_fg Ĝ(4 + f, 4 + g) ξ̄_f · ξ̄_g of the centrifugal case of that axis (xx, yy, zz), ξ̄ the M-normalised mode in
// the fields (/gcms/mode_coefficients): the Southwell coefficient of the free part's mode (the spin softening that
// the rotating frame's inertia adds is not in it). nullopt without the centrifugal cases or without modes.
std::optional<Eigen::Vector3d> spin_stiffening(const format::BodyData& body) {
  const format::GeometricStiffness& g = body.geometric_stiffness;
  const Eigen::Index n_f = body.gcms.field_count();
  if (body.modes.count() == 0 || body.gcms.mode_coefficients.cols() < 3) return std::nullopt;
  const Eigen::MatrixXd shape = body.gcms.mode_coefficients.leftCols(3);  // ξ̄_f of mode 1, one row per field
  Eigen::Vector3d s;
  for (int axis = 0; axis < 3; ++axis) {
    const std::string name = std::string("centrifugal:") + "xyz"[axis] + "xyz"[axis];
    const auto it = std::find(g.cases.begin(), g.cases.end(), name);
    if (it == g.cases.end()) return std::nullopt;
    const Eigen::MatrixXd& m = g.matrices[static_cast<std::size_t>(it - g.cases.begin())];
    s(axis) = (shape.transpose() * m.bottomRightCorner(n_f, n_f) * shape).trace();
  }
  return s;
}

}  // namespace

std::string body_report(const format::BodyData& body, const std::filesystem::path& file) {
  std::string r;
  auto line = [&r](std::string_view label, const std::string& value) { r += fmt::format("  {:<22}{}\n", label, value); };
  const auto& p = body.provenance;
  r += fmt::format("{} ({:.3g} MB): flexbody body file, format version {}{}\n", file.string(),
                   static_cast<double>(file_bytes(file)) / 1e6, body.format_version,
                   body.sealed ? ", sealed" : ", unsealed (not protected against damage: fbprep seal converts it)");
  line("created by", fmt::format("{}, {}", printable(p.created_by), printable(p.created_utc)));
  line("source", fmt::format("{} (sha256 {})", printable(p.source_file), printable(p.source_sha256)));
  line("length unit", fmt::format("{}: {}", printable(p.input_unit), printable(p.unit_reason)));
  std::string options;
  for (std::size_t k = 0; k < std::min(p.options.size(), kShownOptions); ++k)
    options += fmt::format("{}{}={}", k ? ", " : "", printable(p.options[k].first), printable(p.options[k].second));
  if (p.options.size() > kShownOptions) options += fmt::format(", ... ({} options in all)", p.options.size());
  line("options", options);

  const auto& m = body.material;
  r += "\nMaterial\n";
  line(printable(m.name), fmt::format("E = {:.4g} Pa, nu = {:.4g}, rho = {:.6g} kg/m^3", m.youngs_modulus, m.poisson_ratio,
                           m.density));
  r += "\nMass properties\n";
  line("mass", fmt::format("{:.6g} kg", body.mass.mass));
  line("centre of mass", vector3(body.mass.center_of_mass_input) + " m (input frame)");
  for (int i = 0; i < 3; ++i)
    line(i == 0 ? "inertia about CoM" : "",
         vector3(body.mass.inertia_about_com.row(i).transpose()) + (i == 0 ? " kg m^2" : ""));

  const auto& mesh = body.mesh;
  r += "\nMesh (body frame: origin at the centre of mass)\n";
  line("nodes", fmt::format("{} ({} DOFs)", mesh.nodes.rows(), 3 * mesh.nodes.rows()));
  line("tetrahedra", fmt::format("{} (order {}: {} nodes each)", mesh.tets.rows(), mesh.element_order, mesh.tets.cols()));
  line("surface triangles", std::to_string(mesh.surface_triangles.rows()));
  line("bounding box", vector3(mesh.nodes.colwise().minCoeff().transpose()) + " .. " +
                           vector3(mesh.nodes.colwise().maxCoeff().transpose()) + " m");

  const auto& modes = body.modes;
  r += fmt::format("\nModes ({}, {} by {})\n", modes.count(), printable(modes.kind), printable(modes.eigensolver));
  r += fmt::format("  {:>4}  {:>16}  {:>14}\n", "mode", "frequency [Hz]", "rel. residual");
  const Eigen::Index first_static = modes.count() - modes.static_correction_modes;
  for (Eigen::Index k = 0; k < modes.count(); ++k)
    r += fmt::format("  {:>4}  {:>16.6f}  {:>14.2e}{}\n", k + 1, modes.frequencies_hz(k), modes.relative_residuals(k),
                     k >= first_static ? "  static correction (Ritz value)" : "");
  if (!modes.static_loads.empty()) {
    std::string loads;
    for (const std::string& label : modes.static_loads) {
      if (!loads.empty()) loads += ' ';
      loads += printable(label);  // appended: GCC 12 warns falsely on "literal" + std::string&&
    }
    line("static loads", loads);
  }

  const auto& fixed = modes.fixed_interface_frequencies_hz;
  if (fixed.size() > 0) {
    std::string list;
    for (Eigen::Index k = 0; k < fixed.size(); ++k) list += fmt::format("{}{:.6g}", k ? ", " : "", fixed(k));
    line("fixed-interface [Hz]", list);
  }
  const auto& g = body.gcms;
  const auto [k_low, k_high] = stiffness_frequency_range(g.stiffness);
  r += "\nGCMS constants\n";
  line("fields", fmt::format("{} of {} ({} dropped as dependent, tolerance {:.0e})", g.field_count(),
                             g.mode_coefficients.cols(), g.mode_coefficients.cols() - g.field_count(), g.drop_tolerance));
  // The Jacobi-scaled condition numbers are unit-free (the same at every size of the part); the SI ones
  // mix kg, kg m^2 and 1. Older files may not record the scaled one before.
  const std::string scaled_before = g.condition_mass_scaled_before
                                        ? fmt::format("{:.3g} before", *g.condition_mass_scaled_before)
                                        : std::string("before not recorded");
  line("G", fmt::format("{} x {}; cond {:.3g} Jacobi-scaled ({}); in SI units {:.3g} ({:.3g} before)",
                        g.mass_matrix.rows(), g.mass_matrix.cols(), g.condition_mass_scaled_after, scaled_before,
                        g.condition_mass_after, g.condition_mass_before));
  line("K_hat", fmt::format("{} x {}; sqrt(eig)/2pi from {:.6g} to {:.6g} Hz", g.stiffness.rows(), g.stiffness.cols(),
                            k_low, k_high));
  line("cond(Ups^T M_s Ups)", fmt::format("{:.3g} (the modes' own fields)", g.condition_mode_gram_before));
  if (!body.interfaces.empty()) {
    r += "\nInterfaces (body frame)\n";
    for (const format::Interface& i : body.interfaces)
      line(printable(i.name), fmt::format("{}, {} nodes, reference point {} m", printable(i.coupling), i.nodes.size(),
                                          vector3(i.reference_point)));
  }
  if (!body.geometric_stiffness.empty()) {
    r += "\nGeometric stiffness (prestress cases, inertia relief)\n";
    std::vector<std::pair<std::string, int>> sources;  // "centrifugal" or an interface, and its count of cases
    for (const std::string& name : body.geometric_stiffness.cases) {
      const std::string source = name.substr(0, name.rfind(':'));
      if (sources.empty() || sources.back().first != source) sources.emplace_back(source, 0);
      ++sources.back().second;
    }
    std::string listed;
    for (const auto& [source, count] : sources) listed += fmt::format("{}{} ({})", listed.empty() ? "" : ", ", source, count);
    line("cases", fmt::format("{}: {}", body.geometric_stiffness.cases.size(), printable(listed)));
    if (const auto s = spin_stiffening(body))
      line("mode 1 under spin", fmt::format("omega_1^2 + S Omega^2 with S = {:.4g} (about x), {:.4g} (y), {:.4g} (z); "
                                            "S - 1 for motion in the plane of rotation", (*s)(0), (*s)(1), (*s)(2)));
  }
  r += "\nStress recovery\n";
  if (body.recovery.empty()) line("output regions", "none");
  for (const format::RecoveryRegion& region : body.recovery)
    line(printable(region.name), fmt::format("{} nodes, stress modes {} x {}", region.nodes.size(), region.stress_modes.rows(),
                                  region.stress_modes.cols()));
  return r;
}

std::string body_json(const format::BodyData& body, const std::filesystem::path& file) {
  nlohmann::ordered_json j;
  const auto& p = body.provenance;
  j["file"] = file.string();
  j["file_bytes"] = file_bytes(file);
  j["format_version"] = body.format_version;
  j["sealed"] = body.sealed;
  j["created_by"] = capped(p.created_by);
  j["created_utc"] = capped(p.created_utc);
  j["source_file"] = capped(p.source_file);
  j["source_sha256"] = capped(p.source_sha256);
  j["input_unit"] = capped(p.input_unit);
  j["unit_reason"] = capped(p.unit_reason);
  j["declared_unit"] = p.declared_unit.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(capped(p.declared_unit));
  nlohmann::ordered_json options = nlohmann::ordered_json::object();
  for (const auto& [name, value] : p.options) options[capped(name)] = capped(value);
  j["options"] = options;
  j["material"] = {{"name", capped(body.material.name)},
                   {"E_pa", body.material.youngs_modulus},
                   {"nu", body.material.poisson_ratio},
                   {"rho_kgm3", body.material.density}};
  j["mass_kg"] = body.mass.mass;
  const Eigen::Vector3d& c = body.mass.center_of_mass_input;
  j["center_of_mass_m"] = {c(0), c(1), c(2)};
  const Eigen::Matrix3d& inertia = body.mass.inertia_about_com;
  j["inertia_kgm2"] = {{inertia(0, 0), inertia(0, 1), inertia(0, 2)},
                       {inertia(1, 0), inertia(1, 1), inertia(1, 2)},
                       {inertia(2, 0), inertia(2, 1), inertia(2, 2)}};
  j["element_order"] = body.mesh.element_order;
  j["nodes"] = body.mesh.nodes.rows();
  j["dofs"] = 3 * body.mesh.nodes.rows();
  j["elements"] = body.mesh.tets.rows();
  j["surface_triangles"] = body.mesh.surface_triangles.rows();
  j["modes_kind"] = capped(body.modes.kind);
  j["eigensolver"] = capped(body.modes.eigensolver);
  const auto& f = body.modes.frequencies_hz;
  j["frequencies_hz"] = std::vector<double>(f.data(), f.data() + f.size());
  const auto& fixed = body.modes.fixed_interface_frequencies_hz;
  j["fixed_interface_frequencies_hz"] = std::vector<double>(fixed.data(), fixed.data() + fixed.size());
  const auto& res = body.modes.relative_residuals;
  j["relative_residuals"] = std::vector<double>(res.data(), res.data() + res.size());
  const auto& g = body.gcms;
  const auto [k_low, k_high] = stiffness_frequency_range(g.stiffness);
  j["gcms_fields"] = g.field_count();
  j["dropped_fields"] = g.mode_coefficients.cols() - g.field_count();
  j["drop_tolerance"] = g.drop_tolerance;
  j["condition_mode_gram_before"] = number_or_null(g.condition_mode_gram_before);
  j["condition_G_before"] = number_or_null(g.condition_mass_before);
  j["condition_G_after"] = number_or_null(g.condition_mass_after);
  j["condition_G_scaled_before"] =  // null: singular, or not recorded (older files)
      g.condition_mass_scaled_before ? number_or_null(*g.condition_mass_scaled_before)
                                     : nlohmann::ordered_json(nullptr);
  j["condition_G_scaled_after"] = number_or_null(g.condition_mass_scaled_after);
  j["k_hat_frequency_range_hz"] = {k_low, k_high};
  std::vector<std::string> loads;
  for (const std::string& label : body.modes.static_loads) loads.push_back(capped(label));
  j["static_loads"] = loads;
  j["static_correction_modes"] = body.modes.static_correction_modes;
  nlohmann::ordered_json interfaces = nlohmann::ordered_json::array();
  for (const format::Interface& i : body.interfaces)
    interfaces.push_back({{"name", capped(i.name)}, {"coupling", capped(i.coupling)}, {"nodes", i.nodes.size()}});
  j["interfaces"] = interfaces;
  nlohmann::ordered_json regions = nlohmann::ordered_json::array();
  for (const format::RecoveryRegion& region : body.recovery)
    regions.push_back({{"name", capped(region.name)}, {"nodes", region.nodes.size()}});
  j["output_regions"] = regions;
  std::vector<std::string> cases;
  for (const std::string& name : body.geometric_stiffness.cases) cases.push_back(capped(name));
  j["geometric_stiffness_cases"] = cases;
  const std::optional<Eigen::Vector3d> spin = spin_stiffening(body);
  j["spin_stiffening_mode_1"] = spin ? nlohmann::ordered_json({(*spin)(0), (*spin)(1), (*spin)(2)}) : nlohmann::ordered_json(nullptr);
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace flexbody::preprocess
