// body_file_writer.cpp: write_body_file(), the layout of SCHEMA.md, sealed and written atomically.
#include "hdf5_io.hpp"
#include "sealed_write.hpp"

#include "flexbody/format/body_file.hpp"

#include <span>

namespace flexbody::format {
namespace {

using detail::Location;

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

std::span<const double> values_of(const Eigen::VectorXd& v) {
  return {v.data(), static_cast<std::size_t>(v.size())};
}

std::size_t rows_of(const auto& m) { return static_cast<std::size_t>(m.rows()); }
std::size_t cols_of(const auto& m) { return static_cast<std::size_t>(m.cols()); }

void write_root(const Location& root, const Provenance& p) {
  detail::write_string_attribute(root, "format", kFormatName);
  detail::write_int_attribute(root, "format_version", kFormatVersion);
  detail::write_string_attribute(root, "length_unit", "m");
  detail::write_string_attribute(root, "mass_unit", "kg");
  detail::write_string_attribute(root, "time_unit", "s");
  detail::write_string_attribute(root, "created_by", p.created_by);
  detail::write_string_attribute(root, "created_utc", p.created_utc);
  detail::write_string_attribute(root, "source_file", p.source_file);
  detail::write_string_attribute(root, "source_sha256", p.source_sha256);
  detail::write_string_attribute(root, "input_unit", p.input_unit);
  detail::write_string_attribute(root, "unit_reason", p.unit_reason);
  detail::write_string_attribute(root, "declared_unit", p.declared_unit);
}

void write_provenance(const Location& root, const Provenance& p) {
  const Location group = detail::create_group(root, "provenance");
  const Location options = detail::create_group(group, "options");
  std::string order;
  for (const auto& [name, value] : p.options) {
    detail::write_string_attribute(options, name, value);
    order += (order.empty() ? "" : ",") + name;
  }
  detail::write_string_attribute(options, "order", order);
}

void write_material(const Location& root, const Material& material) {
  const Location group = detail::create_group(root, "material");
  detail::write_string_attribute(group, "name", material.name);
  detail::write_double_attribute(group, "youngs_modulus", material.youngs_modulus);
  detail::write_double_attribute(group, "poisson_ratio", material.poisson_ratio);
  detail::write_double_attribute(group, "density", material.density);
}

void write_mass(const Location& root, const MassProperties& mass) {
  const Location group = detail::create_group(root, "mass");
  detail::write_double_attribute(group, "total", mass.mass);
  detail::write_double_vector_attribute(group, "center_of_mass_input",
                                        {mass.center_of_mass_input.data(), 3});
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> inertia = mass.inertia_about_com;
  detail::write_matrix(group, "inertia_about_com", 3, 3, inertia.data(), "kg m^2");
}

void write_mesh(const Location& root, const BodyMesh& mesh) {
  const Location group = detail::create_group(root, "mesh");
  detail::write_matrix(group, "nodes", rows_of(mesh.nodes), 3, mesh.nodes.data(), "m");
  detail::write_matrix(group, "tets", rows_of(mesh.tets), static_cast<std::size_t>(mesh.tets.cols()), mesh.tets.data(),
                       "");
  detail::write_matrix(group, "surface_triangles", rows_of(mesh.surface_triangles), 3,
                       mesh.surface_triangles.data(), "");
  detail::write_int_attribute(group, "element_order", mesh.element_order);
}

void write_modes(const Location& root, const Modes& modes) {
  const Location group = detail::create_group(root, "reduction");
  detail::write_string_attribute(group, "kind", modes.kind);
  detail::write_string_attribute(group, "eigensolver", modes.eigensolver);
  detail::write_double_attribute(group, "shift", modes.shift);
  detail::write_vector(group, "frequencies_hz", values_of(modes.frequencies_hz), "Hz");
  detail::write_vector(group, "relative_residuals", values_of(modes.relative_residuals), "1");
  detail::write_vector(group, "fixed_interface_frequencies_hz", values_of(modes.fixed_interface_frequencies_hz), "Hz");
  std::string loads;
  for (const std::string& label : modes.static_loads) loads += (loads.empty() ? "" : ",") + label;
  detail::write_string_attribute(group, "static_loads", loads);
  detail::write_int_attribute(group, "static_correction_modes", static_cast<int>(modes.static_correction_modes));
  const RowMatrixXd upsilon = modes.upsilon;  // the file is row-major, Eigen::MatrixXd column-major
  detail::write_matrix(group, "upsilon", rows_of(upsilon), cols_of(upsilon), upsilon.data(), "kg^-1/2");
}

void write_gcms(const Location& root, const Gcms& gcms) {
  const Location group = detail::create_group(root, "gcms");
  const RowMatrixXd fields = gcms.fields;
  detail::write_matrix(group, "fields", rows_of(fields), cols_of(fields), fields.data(), "kg^-1/2");
  const std::vector<std::int32_t> field_mode(gcms.field_mode.data(), gcms.field_mode.data() + gcms.field_mode.size());
  detail::write_int_vector(group, "field_mode", field_mode, "");
  const RowMatrixXd coefficients = gcms.mode_coefficients;
  detail::write_matrix(group, "mode_coefficients", rows_of(coefficients), cols_of(coefficients), coefficients.data(),
                       "1");
  const RowMatrixXd g = gcms.mass_matrix;  // symmetric, but written in the file's row-major order anyway
  detail::write_matrix(group, "G", rows_of(g), cols_of(g), g.data(), "mixed: see SCHEMA.md");
  const RowMatrixXd k_hat = gcms.stiffness;
  detail::write_matrix(group, "K_hat", rows_of(k_hat), cols_of(k_hat), k_hat.data(), "s^-2");
  detail::write_double_attribute(group, "drop_tolerance", gcms.drop_tolerance);
  detail::write_int_attribute(group, "dropped_fields",
                              static_cast<int>(gcms.mode_coefficients.cols() - gcms.field_count()));
  detail::write_double_attribute(group, "condition_mode_gram_before", gcms.condition_mode_gram_before);
  detail::write_double_attribute(group, "condition_G_before", gcms.condition_mass_before);
  detail::write_double_attribute(group, "condition_G_after", gcms.condition_mass_after);
  if (gcms.condition_mass_scaled_before)  // optional: readers of older files find it absent
    detail::write_double_attribute(group, "condition_G_scaled_before", *gcms.condition_mass_scaled_before);
  detail::write_double_attribute(group, "condition_G_scaled_after", gcms.condition_mass_scaled_after);
}

void write_interfaces(const Location& root, const std::vector<Interface>& interfaces) {
  const Location group = detail::create_group(root, "interfaces");
  std::string order;
  for (const Interface& i : interfaces) order += (order.empty() ? "" : ",") + i.name;
  detail::write_string_attribute(group, "order", order);
  for (const Interface& i : interfaces) {
    const Location g = detail::create_group(group, i.name);
    detail::write_string_attribute(g, "coupling", i.coupling);
    detail::write_double_vector_attribute(g, "reference_point", {i.reference_point.data(), 3});
    const std::vector<std::int32_t> nodes(i.nodes.data(), i.nodes.data() + i.nodes.size());
    detail::write_int_vector(g, "nodes", nodes, "");
    detail::write_vector(g, "weights", values_of(i.weights), "1");
    detail::write_vector(g, "y_row", values_of(i.y_row), "mixed: see SCHEMA.md");
    const RowMatrixXd rotation = i.rotation;
    detail::write_matrix(g, "rotation", rows_of(rotation), cols_of(rotation), rotation.data(), "kg^-1/2 m^-1");
  }
}

void write_recovery(const Location& root, const std::vector<RecoveryRegion>& regions) {
  const Location group = detail::create_group(root, "recovery");
  std::string order;
  for (const RecoveryRegion& r : regions) order += (order.empty() ? "" : ",") + r.name;
  detail::write_string_attribute(group, "order", order);
  detail::write_string_attribute(group, "stress_components", "xx,yy,zz,xy,xz,yz");
  for (const RecoveryRegion& r : regions) {
    const Location g = detail::create_group(group, r.name);
    const std::vector<std::int32_t> nodes(r.nodes.data(), r.nodes.data() + r.nodes.size());
    detail::write_int_vector(g, "nodes", nodes, "");
    const RowMatrixXd stress = r.stress_modes;
    detail::write_matrix(g, "stress_modes", rows_of(stress), cols_of(stress), stress.data(), "Pa kg^-1/2 m^-1");
  }
}

// Optional: written only when there are cases. The matrices stacked: rows k (4 + n_f) ... of case k.
void write_geometric_stiffness(const Location& root, const GeometricStiffness& stiffness) {
  if (stiffness.empty()) return;
  const Location group = detail::create_group(root, "geometric_stiffness");
  std::string cases;
  for (const std::string& c : stiffness.cases) cases += (cases.empty() ? "" : ",") + c;
  detail::write_string_attribute(group, "cases", cases);
  const Eigen::Index size = stiffness.matrices.front().rows();
  RowMatrixXd stacked(size * static_cast<Eigen::Index>(stiffness.matrices.size()), size);
  for (std::size_t k = 0; k < stiffness.matrices.size(); ++k)
    stacked.middleRows(static_cast<Eigen::Index>(k) * size, size) = stiffness.matrices[k];
  detail::write_matrix(group, "matrices", rows_of(stacked), cols_of(stacked), stacked.data(), "mixed: see SCHEMA.md");
}

/// Writes the whole layout into the new file `file`.
void write_layout(const BodyData& body, const Location& file) {
  write_root(file, body.provenance);
  write_provenance(file, body.provenance);
  write_material(file, body.material);
  write_mass(file, body.mass);
  write_mesh(file, body.mesh);
  write_modes(file, body.modes);
  write_gcms(file, body.gcms);
  write_interfaces(file, body.interfaces);
  write_recovery(file, body.recovery);
  write_geometric_stiffness(file, body.geometric_stiffness);
}

}  // namespace

void write_body_file(const BodyData& body, const std::filesystem::path& path) {
  validate(body);
  detail::write_sealed_file(path, path.string(), [&body](const Location& file) { write_layout(body, file); });
}

}  // namespace flexbody::format
