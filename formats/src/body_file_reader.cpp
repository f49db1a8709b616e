// body_file_reader.cpp: read_body_file(), checking a file against SCHEMA.md.
//
// Order of the checks: the file is a regular, readable file, read into memory once; its seal matches those bytes
// (before the HDF5 library parses anything; a file without a seal is refused too unless ReadOptions say otherwise);
// it is HDF5 with hard links only, says format "flexbody" and a supported format_version (4, sealed; 3, never
// sealed, read only with require_seal off), holds every required group, dataset (contiguous, unfiltered, stored in
// the file) and attribute, has consistent shapes, finite values, and finally passes the same checks as validate().
#include "body_checks.hpp"
#include "body_file_seal.hpp"
#include "file_image.hpp"
#include "hdf5_structure.hpp"
#include "hdf5_io.hpp"

#include "flexbody/format/body_file.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace flexbody::format {
namespace {

using detail::Location;

enum class Item { group, dataset, attribute };

struct Required {
  Item kind;
  const char* path;  ///< for an attribute: path of its object, '/', attribute name
};

// Listed parents first, so that each entry's parent group is known to exist when it is checked.
constexpr Required kRequired[] = {
    {Item::attribute, "/length_unit"},          {Item::attribute, "/mass_unit"},
    {Item::attribute, "/time_unit"},            {Item::attribute, "/created_by"},
    {Item::attribute, "/created_utc"},          {Item::attribute, "/source_file"},
    {Item::attribute, "/source_sha256"},        {Item::attribute, "/input_unit"},
    {Item::attribute, "/unit_reason"},          {Item::group, "/provenance"},
    {Item::group, "/provenance/options"},       {Item::attribute, "/provenance/options/order"},
    {Item::group, "/material"},                 {Item::attribute, "/material/name"},
    {Item::attribute, "/material/youngs_modulus"}, {Item::attribute, "/material/poisson_ratio"},
    {Item::attribute, "/material/density"},     {Item::group, "/mass"},
    {Item::attribute, "/mass/total"},           {Item::attribute, "/mass/center_of_mass_input"},
    {Item::dataset, "/mass/inertia_about_com"}, {Item::group, "/mesh"},
    {Item::dataset, "/mesh/nodes"},             {Item::dataset, "/mesh/tets"},
    {Item::dataset, "/mesh/surface_triangles"}, {Item::attribute, "/mesh/element_order"},
    {Item::group, "/reduction"},                {Item::attribute, "/reduction/kind"},
    {Item::attribute, "/reduction/eigensolver"},    {Item::attribute, "/reduction/shift"},
    {Item::dataset, "/reduction/frequencies_hz"},   {Item::dataset, "/reduction/relative_residuals"},
    {Item::dataset, "/reduction/upsilon"},          {Item::group, "/gcms"},
    {Item::dataset, "/gcms/fields"},            {Item::dataset, "/gcms/field_mode"},
    {Item::dataset, "/gcms/mode_coefficients"}, {Item::dataset, "/gcms/G"},
    {Item::dataset, "/gcms/K_hat"},             {Item::attribute, "/gcms/drop_tolerance"},
    {Item::attribute, "/gcms/dropped_fields"},  {Item::attribute, "/gcms/condition_mode_gram_before"},
    {Item::attribute, "/gcms/condition_G_before"}, {Item::attribute, "/gcms/condition_G_after"},
    {Item::attribute, "/gcms/condition_G_scaled_after"},
    {Item::group, "/interfaces"},               {Item::attribute, "/interfaces/order"},
};

/// Checks /format and /format_version; returns the version.
int check_identity(const Location& root) {
  if (!detail::has_attribute(root, "/", "format")) {
    root.fail("missing root attribute /format; this HDF5 file is not a flexbody body file");
  }
  const std::string format = detail::read_string_attribute(root, "format");
  if (format != kFormatName) {
    root.fail("/format is \"" + format + "\", expected \"" + kFormatName + "\"; not a flexbody body file");
  }
  const int version = detail::read_int_attribute(root, "format_version");
  if (version != kFormatVersion && version != kUnsealedFormatVersion) {
    root.fail("format_version " + std::to_string(version) + " is not supported by this reader (supports " +
              std::to_string(kUnsealedFormatVersion) + " and " + std::to_string(kFormatVersion) +
              "); re-run fbprep to write the current version");
  }
  return version;
}

void check_presence(const Location& root) {
  for (const Required& item : kRequired) {
    const std::string path = item.path;
    if (item.kind == Item::attribute) {
      const std::size_t slash = path.rfind('/');
      const std::string object = slash == 0 ? "/" : path.substr(0, slash);
      if (!detail::has_attribute(root, object, path.substr(slash + 1))) root.fail("missing attribute " + path);
      continue;
    }
    const detail::ObjectKind kind = detail::object_kind(root, path);
    const bool want_group = item.kind == Item::group;
    if (kind == detail::ObjectKind::missing) {
      root.fail(std::string("missing ") + (want_group ? "group " : "dataset ") + path);
    }
    if (kind != (want_group ? detail::ObjectKind::group : detail::ObjectKind::dataset)) {
      root.fail(path + " is not " + (want_group ? "a group" : "a dataset"));
    }
  }
  for (const auto& [name, unit] : {std::pair{"length_unit", "m"}, {"mass_unit", "kg"}, {"time_unit", "s"}}) {
    const std::string found = detail::read_string_attribute(root, name);
    if (found != unit) {
      root.fail(std::string("/") + name + " is \"" + found + "\", expected \"" + unit +
                "\" (the format stores SI units only)");
    }
  }
}

/// Throws unless `table` has `cols` columns and, if `rows` is given, `rows` rows.
template <class T>
void expect_shape(const Location& group, const char* name, const detail::Table<T>& table,
                  std::optional<std::size_t> rows, std::size_t cols, const char* rows_text) {
  if (table.cols != cols || (rows && table.rows != *rows)) {
    group.fail(group.child(name) + " has shape " + std::to_string(table.rows) + " x " + std::to_string(table.cols) +
               ", expected " + rows_text + " x " + std::to_string(cols));
  }
}

template <class Matrix, class T>
Matrix to_matrix(const detail::Table<T>& table) {
  using RowMajor = Eigen::Matrix<typename Matrix::Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const auto rows = static_cast<Eigen::Index>(table.rows);
  const auto cols = static_cast<Eigen::Index>(table.cols);
  return Matrix(Eigen::Map<const RowMajor>(table.values.data(), rows, cols));
}

Eigen::VectorXd to_vector(const std::vector<double>& values) {
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

/// The names in an `order` attribute: comma-separated, "" for none.
std::vector<std::string> names_in_order(const std::string& order) {
  std::vector<std::string> names;
  for (std::size_t begin = 0; begin < order.size();) {
    const std::size_t end = std::min(order.find(',', begin), order.size());
    names.push_back(order.substr(begin, end - begin));
    begin = end + 1;
  }
  return names;
}

Provenance read_provenance(const Location& root) {
  Provenance p;
  p.created_by = detail::read_string_attribute(root, "created_by");
  p.created_utc = detail::read_string_attribute(root, "created_utc");
  p.source_file = detail::read_string_attribute(root, "source_file");
  p.source_sha256 = detail::read_string_attribute(root, "source_sha256");
  p.input_unit = detail::read_string_attribute(root, "input_unit");
  p.unit_reason = detail::read_string_attribute(root, "unit_reason");
  if (detail::has_attribute(root, "/", "declared_unit"))  // optional: absent in older files
    p.declared_unit = detail::read_string_attribute(root, "declared_unit");
  const Location options = detail::open_group(detail::open_group(root, "provenance"), "options");
  for (const std::string& name : names_in_order(detail::read_string_attribute(options, "order")))
    p.options.emplace_back(name, detail::read_string_attribute(options, name));
  return p;
}

Material read_material(const Location& root) {
  const Location group = detail::open_group(root, "material");
  Material material;
  material.name = detail::read_string_attribute(group, "name");
  material.youngs_modulus = detail::read_double_attribute(group, "youngs_modulus");
  material.poisson_ratio = detail::read_double_attribute(group, "poisson_ratio");
  material.density = detail::read_double_attribute(group, "density");
  return material;
}

MassProperties read_mass(const Location& root) {
  const Location group = detail::open_group(root, "mass");
  MassProperties mass;
  mass.mass = detail::read_double_attribute(group, "total");
  const std::vector<double> com = detail::read_double_vector_attribute(group, "center_of_mass_input", 3);
  mass.center_of_mass_input = Eigen::Vector3d(com[0], com[1], com[2]);
  const detail::Table<double> inertia = detail::read_double_matrix(group, "inertia_about_com");
  expect_shape(group, "inertia_about_com", inertia, 3, 3, "3");
  mass.inertia_about_com = to_matrix<Eigen::Matrix3d>(inertia);
  return mass;
}

BodyMesh read_mesh(const Location& root) {
  const Location group = detail::open_group(root, "mesh");
  BodyMesh mesh;
  const detail::Table<double> nodes = detail::read_double_matrix(group, "nodes");
  expect_shape(group, "nodes", nodes, std::nullopt, 3, "n_n");
  mesh.element_order = detail::read_int_attribute(group, "element_order");
  if (mesh.element_order != 1 && mesh.element_order != 2)
    group.fail(group.child("element_order") + " is " + std::to_string(mesh.element_order) +
               ", expected 1 (linear 4-node tetrahedra) or 2 (quadratic 10-node tetrahedra)");
  const detail::Table<std::int32_t> tets = detail::read_int_matrix(group, "tets");
  expect_shape(group, "tets", tets, std::nullopt,
               static_cast<std::size_t>(BodyMesh::nodes_per_element(mesh.element_order)),
               mesh.element_order == 2 ? "n_e (element_order 2)" : "n_e (element_order 1)");
  const detail::Table<std::int32_t> triangles = detail::read_int_matrix(group, "surface_triangles");
  expect_shape(group, "surface_triangles", triangles, std::nullopt, 3, "n_t");
  mesh.nodes = to_matrix<RowMatrixX3d>(nodes);
  mesh.tets = to_matrix<RowMatrixXi>(tets);
  mesh.surface_triangles = to_matrix<RowMatrixX3i>(triangles);
  return mesh;
}

Modes read_modes(const Location& root) {
  const Location group = detail::open_group(root, "reduction");
  Modes modes;
  modes.kind = detail::read_string_attribute(group, "kind");
  modes.eigensolver = detail::read_string_attribute(group, "eigensolver");
  modes.shift = detail::read_double_attribute(group, "shift");
  modes.frequencies_hz = to_vector(detail::read_double_vector(group, "frequencies_hz"));
  modes.relative_residuals = to_vector(detail::read_double_vector(group, "relative_residuals"));
  // Optional: absent means none (files written before Craig-Bampton existed).
  if (detail::object_kind(root, "/reduction/fixed_interface_frequencies_hz") != detail::ObjectKind::missing)
    modes.fixed_interface_frequencies_hz =
        to_vector(detail::read_double_vector(group, "fixed_interface_frequencies_hz"));
  // Optional: absent means no static correction (files written before load points existed).
  if (detail::has_attribute(root, "/reduction", "static_loads"))
    modes.static_loads = names_in_order(detail::read_string_attribute(group, "static_loads"));
  if (detail::has_attribute(root, "/reduction", "static_correction_modes"))
    modes.static_correction_modes = detail::read_int_attribute(group, "static_correction_modes");
  modes.upsilon = to_matrix<Eigen::MatrixXd>(detail::read_double_matrix(group, "upsilon"));
  return modes;
}

Gcms read_gcms(const Location& root) {
  const Location group = detail::open_group(root, "gcms");
  Gcms gcms;
  gcms.fields = to_matrix<Eigen::MatrixXd>(detail::read_double_matrix(group, "fields"));
  const std::vector<std::int32_t> field_mode = detail::read_int_vector(group, "field_mode");
  gcms.field_mode = Eigen::Map<const Eigen::VectorXi>(field_mode.data(), static_cast<Eigen::Index>(field_mode.size()));
  gcms.mode_coefficients = to_matrix<Eigen::MatrixXd>(detail::read_double_matrix(group, "mode_coefficients"));
  gcms.mass_matrix = to_matrix<Eigen::MatrixXd>(detail::read_double_matrix(group, "G"));
  gcms.stiffness = to_matrix<Eigen::MatrixXd>(detail::read_double_matrix(group, "K_hat"));
  gcms.drop_tolerance = detail::read_double_attribute(group, "drop_tolerance");
  gcms.condition_mode_gram_before = detail::read_double_attribute(group, "condition_mode_gram_before");
  gcms.condition_mass_before = detail::read_double_attribute(group, "condition_G_before");
  gcms.condition_mass_after = detail::read_double_attribute(group, "condition_G_after");
  gcms.condition_mass_scaled_after = detail::read_double_attribute(group, "condition_G_scaled_after");
  // Optional: absent in files written before fbprep recorded it.
  if (detail::has_attribute(root, "/gcms", "condition_G_scaled_before"))
    gcms.condition_mass_scaled_before = detail::read_double_attribute(group, "condition_G_scaled_before");
  const int dropped = detail::read_int_attribute(group, "dropped_fields");
  if (dropped != gcms.mode_coefficients.cols() - gcms.fields.cols())
    group.fail("/gcms/dropped_fields is " + std::to_string(dropped) + ", expected 3 n_m - n_f = " +
               std::to_string(gcms.mode_coefficients.cols() - gcms.fields.cols()));
  return gcms;
}

std::vector<Interface> read_interfaces(const Location& root) {
  const Location group = detail::open_group(root, "interfaces");
  std::vector<Interface> interfaces;
  for (const std::string& name : names_in_order(detail::read_string_attribute(group, "order"))) {
    Interface i;
    i.name = name;
    if (i.name.empty() || i.name.find('/') != std::string::npos)
      group.fail("/interfaces/order names an interface \"" + i.name + "\"; names are non-empty and have no '/'");
    const std::string path = "/interfaces/" + i.name;
    if (detail::object_kind(root, path) != detail::ObjectKind::group)
      group.fail("/interfaces/order names \"" + i.name + "\" but there is no group " + path);
    const Location g = detail::open_group(group, i.name);
    for (const char* attribute : {"coupling", "reference_point"})
      if (!detail::has_attribute(root, path, attribute)) group.fail("missing attribute " + path + "/" + attribute);
    i.coupling = detail::read_string_attribute(g, "coupling");
    const std::vector<double> point = detail::read_double_vector_attribute(g, "reference_point", 3);
    i.reference_point = Eigen::Vector3d(point[0], point[1], point[2]);
    const std::vector<std::int32_t> nodes = detail::read_int_vector(g, "nodes");
    i.nodes = Eigen::Map<const Eigen::VectorXi>(nodes.data(), static_cast<Eigen::Index>(nodes.size()));
    i.weights = to_vector(detail::read_double_vector(g, "weights"));
    i.y_row = to_vector(detail::read_double_vector(g, "y_row"));
    i.rotation = to_matrix<Eigen::MatrixXd>(detail::read_double_matrix(g, "rotation"));
    interfaces.push_back(std::move(i));
  }
  return interfaces;
}

// Optional: absent means no output regions (files written before stress recovery existed).
std::vector<RecoveryRegion> read_recovery(const Location& root) {
  std::vector<RecoveryRegion> regions;
  if (detail::object_kind(root, "/recovery") == detail::ObjectKind::missing) return regions;
  const Location group = detail::open_group(root, "recovery");
  for (const char* attribute : {"order", "stress_components"})
    if (!detail::has_attribute(root, "/recovery", attribute)) group.fail(std::string("missing attribute /recovery/") + attribute);
  const std::string components = detail::read_string_attribute(group, "stress_components");
  if (components != "xx,yy,zz,xy,xz,yz")
    group.fail("/recovery/stress_components is \"" + components + "\", expected \"xx,yy,zz,xy,xz,yz\"");
  for (const std::string& name : names_in_order(detail::read_string_attribute(group, "order"))) {
    RecoveryRegion r;
    r.name = name;
    if (r.name.empty() || r.name.find('/') != std::string::npos)
      group.fail("/recovery/order names a region \"" + r.name + "\"; names are non-empty and have no '/'");
    const std::string path = "/recovery/" + r.name;
    if (detail::object_kind(root, path) != detail::ObjectKind::group)
      group.fail("/recovery/order names \"" + r.name + "\" but there is no group " + path);
    const Location g = detail::open_group(group, r.name);
    const std::vector<std::int32_t> nodes = detail::read_int_vector(g, "nodes");
    r.nodes = Eigen::Map<const Eigen::VectorXi>(nodes.data(), static_cast<Eigen::Index>(nodes.size()));
    r.stress_modes = to_matrix<Eigen::MatrixXd>(detail::read_double_matrix(g, "stress_modes"));
    regions.push_back(std::move(r));
  }
  return regions;
}

// Optional: absent means no geometric stiffness (fbprep not asked for it, or before 0.13). The stacked matrices are
// split by the count of cases; a row count that is no multiple of it is left for check_structure to name.
GeometricStiffness read_geometric_stiffness(const Location& root, Eigen::Index field_count) {
  GeometricStiffness stiffness;
  if (detail::object_kind(root, "/geometric_stiffness") == detail::ObjectKind::missing) return stiffness;
  const Location group = detail::open_group(root, "geometric_stiffness");
  if (!detail::has_attribute(root, "/geometric_stiffness", "cases"))
    group.fail("missing attribute /geometric_stiffness/cases");
  stiffness.cases = names_in_order(detail::read_string_attribute(group, "cases"));
  if (stiffness.cases.empty()) group.fail("/geometric_stiffness/cases names no case");
  // The shape before the values are copied: p (4 + n_f) x (4 + n_f), n_f from /gcms (read before).
  const detail::Table<double> table = detail::read_double_matrix(group, "matrices");
  const auto count = static_cast<Eigen::Index>(stiffness.cases.size()), size = 4 + field_count;
  if (static_cast<Eigen::Index>(table.cols) != size || static_cast<Eigen::Index>(table.rows) / size != count ||
      static_cast<Eigen::Index>(table.rows) % size != 0)
    group.fail("/geometric_stiffness/matrices has shape " + std::to_string(table.rows) + " x " +
               std::to_string(table.cols) + ", expected " + std::to_string(count * size) + " x " + std::to_string(size) +
               " (" + std::to_string(count) + " cases of 4 + n_f rows)");
  const Eigen::MatrixXd stacked = to_matrix<Eigen::MatrixXd>(table);
  for (Eigen::Index k = 0; k < count; ++k) stiffness.matrices.emplace_back(stacked.middleRows(k * size, size));
  return stiffness;
}

}  // namespace

BodyData read_body_file(const std::filesystem::path& path, const ReadOptions& options) {
  const std::string label = path.string();
  // Read once: the seal is checked on exactly the bytes HDF5 parses next.
  std::vector<char> image = detail::read_file_image(path, label);
  const std::string_view bytes(image.data(), image.size());
  const detail::SealCheck seal = detail::check_seal(bytes);
  if (seal.state == detail::SealState::damaged && options.require_seal)
    throw BodyFileDamaged(detail::damaged_message(label, seal.problem));
  if (!detail::is_hdf5_file(bytes)) throw BodyFileError(label + ": not an HDF5 file");
  // A simulator reads only what a seal vouches for: an unsealed file (version 3, or one rewritten by another
  // program) is refused before HDF5 parses it, since libhdf5 can crash or hang on damaged bytes.
  if (seal.state == detail::SealState::absent && options.require_seal) throw BodyFileError(detail::unsealed_message(label));
  // A sealed file's HDF5 metadata is the subset fbprep writes, checked before libhdf5 follows any address in it: a
  // seal can be recomputed, and libhdf5 1.10 crashed on changed addresses of dense storage.
  if (seal.state == detail::SealState::valid && options.require_seal) {
    const std::string problem = detail::check_hdf5_structure(bytes, detail::kSealBytes);
    if (!problem.empty())
      throw BodyFileError(label + ": its HDF5 structure is not what fbprep writes (" + problem +
                          "): altered and sealed again, or written by fbprep 0.6.0, which `fbprep seal " +
                          label + "` converts");
  }
  const detail::QuietHdf5Errors quiet;
  BodyData body;
  body.sealed = seal.state == detail::SealState::valid;
  {
    // Variable-length strings (the global heap) only where the caller accepts unsealed files (fbprep seal):
    // a sealed file never holds them, and a seal proves integrity, not the writer (SCHEMA.md, "Seal").
    const Location root = detail::open_file_image(image, label, !options.require_seal);
    body.format_version = check_identity(root);
    if (body.format_version == kUnsealedFormatVersion && body.sealed)
      root.fail("format_version 3 carries a seal, which only version 4 files have");
    check_presence(root);
    body.provenance = read_provenance(root);
    body.material = read_material(root);
    body.mass = read_mass(root);
    body.mesh = read_mesh(root);
    body.modes = read_modes(root);
    body.gcms = read_gcms(root);
    body.interfaces = read_interfaces(root);
    body.recovery = read_recovery(root);
    body.geometric_stiffness = read_geometric_stiffness(root, body.gcms.field_count());
  }
  image = {};  // the values are in `body` now
  detail::check_structure(body, label);
  detail::check_finite(body, label);
  detail::check_ranges(body, label);
  return body;
}

}  // namespace flexbody::format
