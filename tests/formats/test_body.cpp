// test_body.cpp: fixtures and HDF5 surgery for the format tests.
#include "test_body.hpp"

#include "flexbody/format/body_file.hpp"

#include <hdf5.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <iterator>

namespace flexbody::format::test {
namespace {

/// Closes an HDF5 identifier at scope exit and fails the test if it could not be opened.
class Id {
 public:
  Id(hid_t id, herr_t (*closer)(hid_t), const std::string& what) : id_(id), closer_(closer) {
    EXPECT_GE(id_, 0) << "HDF5 could not open/create " << what;
  }
  ~Id() {
    if (id_ >= 0) closer_(id_);
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  [[nodiscard]] hid_t get() const { return id_; }

 private:
  hid_t id_;
  herr_t (*closer_)(hid_t);
};

Id open_rw(const std::filesystem::path& file) {
  return {H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose, file.string()};
}

void replace_attribute(const std::filesystem::path& file, const std::string& object, const std::string& name,
                       hid_t type, const void* value) {
  const Id f = open_rw(file);
  const Id o(H5Oopen(f.get(), object.c_str(), H5P_DEFAULT), H5Oclose, object);
  if (H5Aexists(o.get(), name.c_str()) > 0) {
    ASSERT_GE(H5Adelete(o.get(), name.c_str()), 0);
  }
  const Id space(H5Screate(H5S_SCALAR), H5Sclose, "scalar space");
  const Id a(H5Acreate2(o.get(), name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, name);
  ASSERT_GE(H5Awrite(a.get(), type, value), 0);
}

void replace_dataset(const std::filesystem::path& file, const std::string& path, std::size_t rows,
                     std::size_t cols, hid_t type, const void* values) {
  const Id f = open_rw(file);
  if (H5Lexists(f.get(), path.c_str(), H5P_DEFAULT) > 0) {
    ASSERT_GE(H5Ldelete(f.get(), path.c_str(), H5P_DEFAULT), 0);
  }
  const hsize_t dims[2] = {rows, cols};
  const Id space(H5Screate_simple(2, dims, nullptr), H5Sclose, "space");
  const Id d(H5Dcreate2(f.get(), path.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
             H5Dclose, path);
  if (values != nullptr) {
    ASSERT_GE(H5Dwrite(d.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), 0);
  }
}

}  // namespace

Eigen::VectorXd mode_shape(const Gcms& gcms, Eigen::Index m) {
  Eigen::VectorXd shape(3 * gcms.mode_coefficients.rows());
  for (Eigen::Index f = 0; f < gcms.mode_coefficients.rows(); ++f)
    shape.segment<3>(3 * f) = gcms.mode_coefficients.row(f).segment<3>(3 * m).transpose();
  return shape;
}

void match_frequencies_to_stiffness(BodyData& body) {
  for (Eigen::Index m = 0; m < body.modes.frequencies_hz.size(); ++m) {
    const Eigen::VectorXd shape = mode_shape(body.gcms, m);
    body.modes.frequencies_hz(m) = std::sqrt(shape.dot(body.gcms.stiffness * shape)) / (2.0 * std::numbers::pi);
  }
}

BodyData make_body() {
  BodyData body;
  body.provenance.created_by = "formats_tests 0.1.0";
  body.provenance.created_utc = "2026-11-21T14:38:08Z";
  body.provenance.source_file = "bracket w\xc3\xb6lfer.step";  // UTF-8 survives
  body.provenance.source_sha256 = std::string(64, 'a');
  body.provenance.input_unit = "mm";
  body.provenance.unit_reason = "declared by the STEP file";
  body.provenance.declared_unit = "mm";
  body.provenance.options = {{"unit", "mm"}, {"modes", "2"}, {"mesh-size", "0.5"}, {"note", ""}};

  body.material = {"steel", 210.0e9 / 3.0, 0.3, 7850.0 + 1.0 / 7.0};

  body.mass.mass = 1.0 / 3.0;
  body.mass.center_of_mass_input = Eigen::Vector3d(0.1 / 3.0, -0.2 / 7.0, 0.3 / 11.0);
  // A physical inertia tensor (each principal value below the sum of the other two), so that the
  // second moments J = tr(I)/2 1 - I in /gcms/G are positive definite.
  body.mass.inertia_about_com << 1.0 / 3.0, 0.01 / 7.0, 0.02 / 9.0,  //
      0.01 / 7.0, 2.0 / 5.0, 0.03 / 11.0,                            //
      0.02 / 9.0, 0.03 / 11.0, 1.0 / 7.0;

  body.mesh.nodes.resize(5, 3);
  body.mesh.nodes << 0.0, 0.0, 0.0, 0.1 / 3.0, 0.0, 0.0, 0.0, 0.1 / 7.0, 0.0, 0.0, 0.0, 0.1 / 9.0,  //
      0.1 / 3.0, 0.1 / 7.0, 0.1 / 9.0;
  body.mesh.tets.resize(2, 4);
  body.mesh.tets << 0, 1, 2, 3,  //
      1, 4, 2, 3;
  body.mesh.surface_triangles.resize(6, 3);
  body.mesh.surface_triangles << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 4, 1, 4, 3, 2, 3, 4;
  body.mesh.element_order = 1;

  body.modes.kind = "free-free";
  body.modes.eigensolver = "spectra";
  body.modes.shift = -1.0 / 3.0;
  body.modes.frequencies_hz = Eigen::Vector2d(1234.0 / 7.0, 5678.0 / 9.0);
  body.modes.relative_residuals = Eigen::Vector2d(1e-12 / 3.0, 2e-11 / 7.0);
  body.modes.upsilon.resize(5, 6);
  for (Eigen::Index i = 0; i < 5; ++i) {
    for (Eigen::Index j = 0; j < 6; ++j) body.modes.upsilon(i, j) = static_cast<double>(10 * i + j) / 3.0 - 7.0;
  }

  // 5 of the 6 fields kept (one dropped), G consistent with /mass and positive definite.
  Gcms& gcms = body.gcms;
  constexpr int kFields = 5;
  gcms.fields.resize(5, kFields);
  for (Eigen::Index i = 0; i < 5; ++i)
    for (Eigen::Index f = 0; f < kFields; ++f) gcms.fields(i, f) = static_cast<double>(7 * i - f) / 11.0;
  gcms.field_mode.resize(kFields);
  gcms.field_mode << 0, 0, 0, 1, 1;
  gcms.mode_coefficients.resize(kFields, 6);
  for (Eigen::Index f = 0; f < kFields; ++f)
    for (Eigen::Index j = 0; j < 6; ++j) gcms.mode_coefficients(f, j) = static_cast<double>(f + 2 * j) / 13.0;
  // Each mode's 3 columns with a unit sum of squares, as for M-orthonormal modes (SCHEMA.md, "GCMS constants").
  for (Eigen::Index m = 0; m < 2; ++m) gcms.mode_coefficients.middleCols(3 * m, 3).normalize();
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(4 + kFields, 4 + kFields);
  g(0, 0) = body.mass.mass;
  const Eigen::Matrix3d& inertia = body.mass.inertia_about_com;
  g.block<3, 3>(1, 1) = 0.5 * inertia.trace() * Eigen::Matrix3d::Identity() - inertia;
  for (int r = 0; r < 3; ++r)
    for (int f = 0; f < kFields; ++f) g(1 + r, 4 + f) = g(4 + f, 1 + r) = static_cast<double>(r - f) / 997.0;
  g.bottomRightCorner(kFields, kFields).setIdentity();
  gcms.mass_matrix = g;
  gcms.stiffness.resize(3 * kFields, 3 * kFields);
  for (Eigen::Index r = 0; r < 3 * kFields; ++r)
    for (Eigen::Index c = 0; c < 3 * kFields; ++c)
      gcms.stiffness(r, c) = static_cast<double>((r + 1) * (c + 1)) / 3.0 + (r == c ? 1e6 / 7.0 : 0.0);
  // The frequencies are the modes' Rayleigh quotients in K̂ (SCHEMA.md, "GCMS constants"): c_mᵀ K̂ c_m = ω_m². K̂
  // is first stiffened along mode 1's shape (symmetric, still positive definite) so that they ascend.
  std::array<Eigen::VectorXd, 2> shapes;
  for (Eigen::Index m = 0; m < 2; ++m) {
    shapes[m].resize(3 * kFields);
    for (Eigen::Index f = 0; f < kFields; ++f)
      shapes[m].segment<3>(3 * f) = gcms.mode_coefficients.row(f).segment<3>(3 * m).transpose();
  }
  gcms.stiffness += (3e5 / 7.0) * shapes[1] * shapes[1].transpose();
  gcms.stiffness = (0.5 * (gcms.stiffness + gcms.stiffness.transpose())).eval();  // symmetric to the last bit
  match_frequencies_to_stiffness(body);
  gcms.drop_tolerance = 1e-8;
  gcms.condition_mode_gram_before = std::numeric_limits<double>::infinity();  // singular: allowed
  gcms.condition_mass_before = 1e9 / 3.0;
  gcms.condition_mass_after = 1e3 / 7.0;
  gcms.condition_mass_scaled_before = 1e5 / 3.0;
  gcms.condition_mass_scaled_after = 1e2 / 7.0;

  // One interface on the face of nodes 1, 2, 4, with weights that are not round numbers.
  Interface face;
  face.name = "bore A";
  face.coupling = "rbe3";
  face.nodes.resize(3);
  face.nodes << 1, 2, 4;
  face.weights = Eigen::Vector3d(1.0 / 3.0, 1.0 / 6.0, 0.5);
  for (Eigen::Index j = 0; j < 3; ++j) face.reference_point += face.weights(j) * body.mesh.nodes.row(face.nodes(j)).transpose();
  face.y_row.resize(4 + kFields);
  face.y_row << 1.0, face.reference_point, Eigen::VectorXd::LinSpaced(kFields, 0.1 / 3.0, 0.5 / 3.0);
  face.rotation.resize(3, 3 * kFields);
  for (Eigen::Index r = 0; r < 3; ++r)
    for (Eigen::Index c = 0; c < 3 * kFields; ++c) face.rotation(r, c) = static_cast<double>(r - c) / 17.0;
  body.interfaces.push_back(face);

  // A static correction mode (the last one) and an output region on nodes 0 and 3.
  body.modes.static_loads = {"bore A:fx", "bore A:mz"};
  body.modes.static_correction_modes = 1;
  RecoveryRegion region;
  region.name = "fillet";
  region.nodes.resize(2);
  region.nodes << 0, 3;
  region.stress_modes.resize(12, 3 * kFields);
  for (Eigen::Index r = 0; r < 12; ++r)
    for (Eigen::Index c = 0; c < 3 * kFields; ++c) region.stress_modes(r, c) = 1e9 * static_cast<double>(r + 2 * c) / 13.0;
  body.recovery.push_back(region);

  // The geometric stiffness of two prestress cases: symmetric, distinct values, row and column 0 zero.
  body.geometric_stiffness.cases = {"centrifugal:zz", "bore A:fx"};
  for (int k = 0; k < 2; ++k) {
    Eigen::MatrixXd stiffness = Eigen::MatrixXd::Zero(4 + kFields, 4 + kFields);
    for (Eigen::Index r = 1; r < stiffness.rows(); ++r)
      for (Eigen::Index c = 1; c <= r; ++c) stiffness(r, c) = stiffness(c, r) = (k + 1) * 0.37 * static_cast<double>(r * 7 + c) / 11.0;
    body.geometric_stiffness.matrices.push_back(stiffness);
  }
  return body;
}

BodyData scaled_body(const BodyData& body, double scale) {
  const double s = scale, s3 = s * s * s, s5 = s3 * s * s;
  const double field = 1.0 / std::sqrt(s3);  // kg^-1/2: the mass grows like s^3
  BodyData b = body;
  b.mass.mass *= s3;
  b.mass.center_of_mass_input *= s;
  b.mass.inertia_about_com *= s5;
  b.mesh.nodes *= s;
  b.modes.frequencies_hz /= s;
  b.modes.fixed_interface_frequencies_hz /= s;
  b.modes.shift /= s * s;
  b.modes.upsilon *= field;
  Gcms& g = b.gcms;
  g.fields *= field;
  g.stiffness /= s * s;
  Eigen::VectorXd rows = Eigen::VectorXd::Ones(g.mass_matrix.rows());  // G_rc x rows_r rows_c
  rows(0) = std::sqrt(s3);
  rows.segment<3>(1).setConstant(std::sqrt(s5));
  g.mass_matrix = rows.asDiagonal() * g.mass_matrix * rows.asDiagonal();
  g.condition_mass_before = g.condition_mass_after = std::numeric_limits<double>::infinity();
  for (Interface& i : b.interfaces) {
    i.reference_point *= s;
    i.y_row.segment<3>(1) *= s;
    i.y_row.tail(i.y_row.size() - 4) *= field;
    i.rotation *= field / s;  // kg^-1/2 m^-1
  }
  for (RecoveryRegion& r : b.recovery) r.stress_modes *= field / s;  // Pa kg^-1/2 m^-1
  return b;
}

void TempDirTest::SetUp() {
  static std::atomic<int> counter{0};
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "-" + info->name();
  std::replace(name.begin(), name.end(), '/', '_');
  dir_ = std::filesystem::temp_directory_path() /
         ("flexbody-formats-" + name + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::filesystem::remove_all(dir_);
  std::filesystem::create_directories(dir_);
}

void TempDirTest::TearDown() {
  std::error_code ignored;
  std::filesystem::remove_all(dir_, ignored);
}

std::vector<std::string> TempDirTest::entries() const {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) names.push_back(entry.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

void expect_body_file_error(const std::function<void()>& action, const std::vector<std::string>& parts) {
  try {
    action();
    ADD_FAILURE() << "expected a BodyFileError, but nothing was thrown";
  } catch (const BodyFileError& error) {
    const std::string message = error.what();
    for (const std::string& part : parts) {
      EXPECT_NE(message.find(part), std::string::npos) << "message \"" << message << "\" lacks \"" << part << "\"";
    }
  } catch (const std::exception& error) {
    ADD_FAILURE() << "expected a BodyFileError, got another exception: " << error.what();
  }
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << "cannot write " << path;
}

void set_string_attribute(const std::filesystem::path& file, const std::string& object, const std::string& name,
                          const std::string& value, bool fixed_length) {
  const Id type(H5Tcopy(H5T_C_S1), H5Tclose, "string type");
  if (fixed_length) {
    ASSERT_GE(H5Tset_size(type.get(), value.size()), 0);
    ASSERT_GE(H5Tset_strpad(type.get(), H5T_STR_NULLPAD), 0);
    replace_attribute(file, object, name, type.get(), value.data());
  } else {
    ASSERT_GE(H5Tset_size(type.get(), H5T_VARIABLE), 0);
    const char* text = value.c_str();
    replace_attribute(file, object, name, type.get(), static_cast<const void*>(&text));
  }
}

void set_int_attribute(const std::filesystem::path& file, const std::string& object, const std::string& name,
                       int value) {
  replace_attribute(file, object, name, H5T_NATIVE_INT, &value);
}

void delete_attribute(const std::filesystem::path& file, const std::string& object, const std::string& name) {
  const Id f = open_rw(file);
  ASSERT_GE(H5Adelete_by_name(f.get(), object.c_str(), name.c_str(), H5P_DEFAULT), 0);
}

void delete_link(const std::filesystem::path& file, const std::string& path) {
  const Id f = open_rw(file);
  ASSERT_GE(H5Ldelete(f.get(), path.c_str(), H5P_DEFAULT), 0);
}

void replace_double_dataset(const std::filesystem::path& file, const std::string& path, std::size_t rows,
                            std::size_t cols, const std::vector<double>& values) {
  ASSERT_EQ(values.size(), rows * cols);
  replace_dataset(file, path, rows, cols, H5T_NATIVE_DOUBLE, values.data());
}

void declare_double_dataset(const std::filesystem::path& file, const std::string& path, std::size_t rows,
                            std::size_t cols) {
  replace_dataset(file, path, rows, cols, H5T_NATIVE_DOUBLE, nullptr);
}

void replace_int_dataset(const std::filesystem::path& file, const std::string& path, std::size_t rows,
                         std::size_t cols, const std::vector<int>& values) {
  ASSERT_EQ(values.size(), rows * cols);
  replace_dataset(file, path, rows, cols, H5T_NATIVE_INT, values.data());
}

RawDataset read_raw_dataset(const std::filesystem::path& file, const std::string& path) {
  RawDataset raw;
  const Id f(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, file.string());
  const Id d(H5Dopen2(f.get(), path.c_str(), H5P_DEFAULT), H5Dclose, path);
  const Id space(H5Dget_space(d.get()), H5Sclose, "space of " + path);
  std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space.get())));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  raw.shape.assign(dims.begin(), dims.end());
  raw.values.resize(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.get())));
  EXPECT_GE(H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.values.data()), 0);
  return raw;
}

std::string read_raw_string_attribute(const std::filesystem::path& file, const std::string& object,
                                      const std::string& name) {
  const Id f(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, file.string());
  const Id a(H5Aopen_by_name(f.get(), object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, name);
  // Version 4 stores fixed-length UTF-8 strings, NUL-padded (SCHEMA.md, "Seal"): read the bytes as stored.
  const Id type(H5Aget_type(a.get()), H5Tclose, "type of " + name);
  EXPECT_EQ(H5Tget_class(type.get()), H5T_STRING) << name;
  EXPECT_EQ(H5Tis_variable_str(type.get()), 0) << name;
  EXPECT_EQ(H5Tget_strpad(type.get()), H5T_STR_NULLPAD) << name;
  EXPECT_EQ(H5Tget_cset(type.get()), H5T_CSET_UTF8) << name;
  std::string bytes(H5Tget_size(type.get()), '\0');
  EXPECT_GE(H5Aread(a.get(), type.get(), bytes.data()), 0);
  return bytes.substr(0, bytes.find('\0'));
}

}  // namespace flexbody::format::test
