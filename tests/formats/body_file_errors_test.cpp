// body_file_errors_test.cpp: the reader refuses bad files with a message naming the file and the item.
#include "test_body.hpp"

#include "flexbody/format/body_file.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <initializer_list>
#include <limits>
#include <vector>

namespace flexbody::format::test {
namespace {

class ReadErrors : public TempDirTest {
 protected:
  /// A valid file to be damaged by the test.
  std::filesystem::path good_file(const std::string& name) {
    const auto path = dir() / name;
    write_body_file(make_body(), path);
    return path;
  }

  /// Reads a file these tests edited with the HDF5 C API, as `fbprep seal` does: the edit broke the seal
  /// (body_file_seal_test.cpp), so the seal is not required and every other check of the reader runs.
  static BodyData read_edited(const std::filesystem::path& path) {
    return read_body_file(path, ReadOptions{.require_seal = false});
  }

  /// Expects read_edited(path) to throw a message that starts with the path and contains `parts`.
  static void expect_read_error(const std::filesystem::path& path, std::initializer_list<std::string> parts) {
    std::vector<std::string> expected{path.string() + ": "};
    expected.insert(expected.end(), parts);
    expect_body_file_error([&] { (void)read_edited(path); }, expected);
  }
};

TEST_F(ReadErrors, MissingFile) { expect_read_error(dir() / "absent.fbh5", {"absent.fbh5: no such file"}); }

TEST_F(ReadErrors, Directory) {
  std::filesystem::create_directory(dir() / "folder.fbh5");
  expect_read_error(dir() / "folder.fbh5", {"is a directory"});
}

TEST_F(ReadErrors, NotHdf5) {
  const auto path = dir() / "text.fbh5";
  write_bytes(path, "this is not HDF5 but has more than eight bytes\n");
  expect_read_error(path, {"text.fbh5: not an HDF5 file"});
}

TEST_F(ReadErrors, EmptyFile) {
  const auto path = dir() / "empty.fbh5";
  write_bytes(path, "");
  expect_read_error(path, {"empty.fbh5: not an HDF5 file"});
}

TEST_F(ReadErrors, OtherFormat) {
  const auto path = good_file("other.fbh5");
  set_string_attribute(path, "/", "format", "other");
  expect_read_error(path, {"other.fbh5: /format is \"other\", expected \"flexbody\""});
}

TEST_F(ReadErrors, FixedLengthStringsAreAccepted) {
  const auto path = good_file("fixed.fbh5");
  set_string_attribute(path, "/", "format", "flexbody", true);
  set_string_attribute(path, "/material", "name", "aluminium", true);
  EXPECT_EQ(read_edited(path).material.name, "aluminium");
}

TEST_F(ReadErrors, PlainHdf5WithoutFormat) {
  const auto path = good_file("plain.fbh5");
  delete_attribute(path, "/", "format");
  expect_read_error(path, {"plain.fbh5: missing root attribute /format"});
}

TEST_F(ReadErrors, FormatVersion1) {
  const auto path = good_file("v1.fbh5");
  set_int_attribute(path, "/", "format_version", 1);
  expect_read_error(path, {"v1.fbh5: format_version 1 is not supported by this reader (supports 3 and 4); re-run "
                           "fbprep to write the current version"});
}

TEST_F(ReadErrors, FormatVersionAsString) {
  const auto path = good_file("vstr.fbh5");
  set_string_attribute(path, "/", "format_version", "1");
  expect_read_error(path, {"vstr.fbh5: /format_version is a string, expected an integer"});
}

TEST_F(ReadErrors, MissingUpsilon) {
  const auto path = good_file("no_upsilon.fbh5");
  delete_link(path, "/reduction/upsilon");
  expect_read_error(path, {"no_upsilon.fbh5: missing dataset /reduction/upsilon"});
}

TEST_F(ReadErrors, MissingGroup) {
  const auto path = good_file("no_mesh.fbh5");
  delete_link(path, "/mesh");
  expect_read_error(path, {"no_mesh.fbh5: missing group /mesh"});
}

TEST_F(ReadErrors, MissingAttribute) {
  const auto path = good_file("no_density.fbh5");
  delete_attribute(path, "/material", "density");
  expect_read_error(path, {"no_density.fbh5: missing attribute /material/density"});
}

TEST_F(ReadErrors, MissingListedOption) {
  const auto path = good_file("no_option.fbh5");
  delete_attribute(path, "/provenance/options", "modes");
  expect_read_error(path, {"no_option.fbh5: missing attribute /provenance/options/modes"});
}

TEST_F(ReadErrors, WrongUpsilonShape) {
  const auto path = good_file("upsilon_shape.fbh5");
  replace_double_dataset(path, "/reduction/upsilon", 5, 9, std::vector<double>(45, 0.5));
  expect_read_error(path, {"upsilon_shape.fbh5: /reduction/upsilon has shape 5 x 9, expected 5 x 6 (n_n x 3 n_m)"});
}

TEST_F(ReadErrors, WrongNodeColumns) {
  const auto path = good_file("nodes_2d.fbh5");
  replace_double_dataset(path, "/mesh/nodes", 5, 2, std::vector<double>(10, 0.5));
  expect_read_error(path, {"nodes_2d.fbh5: /mesh/nodes has shape 5 x 2, expected n_n x 3"});
}

TEST_F(ReadErrors, WrongInertiaShape) {
  const auto path = good_file("inertia.fbh5");
  replace_double_dataset(path, "/mass/inertia_about_com", 1, 3, {1.0, 1.0, 1.0});
  expect_read_error(path, {"inertia.fbh5: /mass/inertia_about_com has shape 1 x 3, expected 3 x 3"});
}

TEST_F(ReadErrors, ResidualsOfWrongLength) {
  const auto path = good_file("residuals.fbh5");
  replace_double_dataset(path, "/reduction/relative_residuals", 3, 1, {0.0, 0.0, 0.0});
  expect_read_error(path, {"residuals.fbh5: /reduction/relative_residuals has shape 3 x 1, expected a 1-D dataset"});
}

TEST_F(ReadErrors, TetIndexOutOfRange) {
  const auto path = good_file("tets.fbh5");
  replace_int_dataset(path, "/mesh/tets", 2, 4, {0, 1, 2, 3, 1, 4, 9, 3});
  expect_read_error(path, {"tets.fbh5: /mesh/tets[1] refers to node 9 but the mesh has 5 nodes"});
}

TEST_F(ReadErrors, TetsStoredAsFloats) {
  const auto path = good_file("float_tets.fbh5");
  replace_double_dataset(path, "/mesh/tets", 2, 4, std::vector<double>(8, 1.0));
  expect_read_error(path, {"float_tets.fbh5: /mesh/tets does not hold integer values"});
}

TEST_F(ReadErrors, NanInNodes) {
  const auto path = good_file("nan.fbh5");
  std::vector<double> nodes(15, 0.25);
  nodes[2 * 3 + 1] = std::numeric_limits<double>::quiet_NaN();
  replace_double_dataset(path, "/mesh/nodes", 5, 3, nodes);
  expect_read_error(path, {"nan.fbh5: /mesh/nodes[2][1] is nan, expected a finite number"});
}

TEST_F(ReadErrors, InfinityInUpsilon) {
  const auto path = good_file("inf.fbh5");
  std::vector<double> upsilon(30, 0.5);
  upsilon[4 * 6 + 5] = -std::numeric_limits<double>::infinity();
  replace_double_dataset(path, "/reduction/upsilon", 5, 6, upsilon);
  expect_read_error(path, {"inf.fbh5: /reduction/upsilon[4][5] is -inf, expected a finite number"});
}

TEST_F(ReadErrors, UnitOtherThanSi) {
  const auto path = good_file("mm.fbh5");
  set_string_attribute(path, "/", "length_unit", "mm");
  expect_read_error(path, {"mm.fbh5: /length_unit is \"mm\", expected \"m\""});
}

// Issue 13: text from a file went into messages as it was: fbsim printed raw newlines, and a 200,000-character
// string became a 200 KB error line. Every message is one line of at most BodyFileError::kMessageLimit bytes.
TEST_F(ReadErrors, TextFromTheFileCannotBreakOrFloodTheMessage) {
  const auto path = good_file("flood.fbh5");
  const std::string flood = "m\nfbsim: all is well\r\n" + std::string(200000, 'x');
  set_string_attribute(path, "/", "length_unit", flood);
  try {
    (void)read_edited(path);
    FAIL() << "accepted";
  } catch (const BodyFileError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find_first_of("\n\r"), std::string::npos);
    EXPECT_LE(message.size(), BodyFileError::kMessageLimit);
    EXPECT_NE(message.find("flood.fbh5: /length_unit is \"m fbsim: all is well  xxx"), std::string::npos) << message;
    EXPECT_NE(message.find("bytes, cut)"), std::string::npos) << message;
  }
  // A short message is kept as it is; a cut never splits a UTF-8 character.
  EXPECT_STREQ(BodyFileError("a.fbh5: short").what(), "a.fbh5: short");
  // 1033 bytes: the cut keeps 1000 − 22 (" ... (1033 bytes, cut)") = 978, where a 2-byte ξ starts at byte 977.
  const std::string cut = BodyFileError(std::string(977, 'a') + "\xce\xbe\xce\xbe" + std::string(52, 'b')).what();
  EXPECT_EQ(cut, std::string(977, 'a') + " ... (1033 bytes, cut)");
}

// Issue 13: a declared shape was trusted before allocating: 10^8 nodes declared in a 158 KB file took 4.7 GB and
// 8-18 s before the refusal. The declared size is now checked against the file's size and the dataset's storage.
TEST_F(ReadErrors, ADeclaredShapeBeyondTheFileIsRefusedBeforeAllocating) {
  const auto path = good_file("huge.fbh5");
  declare_double_dataset(path, "/mesh/nodes", 100000000, 3);
  expect_read_error(path, {"/mesh/nodes declares 100000000 x 3 values (2.4 GB), but the file has "});
  const auto unwritten = good_file("unwritten.fbh5");
  declare_double_dataset(unwritten, "/mesh/nodes", 5, 3);  // fits in the file, but never written: no storage
  expect_read_error(unwritten, {"/mesh/nodes declares 5 x 3 values (120 bytes), but only 0 bytes of them are stored"});
}

// The geometric stiffness's stacked matrices are checked against the cases and n_f before their values are copied:
// a declared (0, 2^62) shape holds no values, so it passed the size check of the file, and with 4 cases the product
// 4 x 2^62 wrapped to 0 rows (helper review). Each shape below is refused by name.
TEST_F(ReadErrors, GeometricStiffnessOfTheWrongShape) {
  const auto path = good_file("stiffness_shape.fbh5");
  replace_double_dataset(path, "/geometric_stiffness/matrices", 9, 9, std::vector<double>(81, 0.0));
  expect_read_error(path, {"/geometric_stiffness/matrices has shape 9 x 9, expected 18 x 9 (2 cases of 4 + n_f rows)"});
  const auto wide = good_file("stiffness_wide.fbh5");
  replace_double_dataset(wide, "/geometric_stiffness/matrices", 0, std::size_t{1} << 62, {});
  expect_read_error(wide, {"/geometric_stiffness/matrices has shape 0 x 4611686018427387904, expected 18 x 9"});
  const auto cases = good_file("stiffness_cases.fbh5");
  set_string_attribute(cases, "/geometric_stiffness", "cases", "");
  expect_read_error(cases, {"/geometric_stiffness/cases names no case"});
}

TEST_F(ReadErrors, PhysicalRangeViolation) {
  const auto path = good_file("nu.fbh5");
  delete_attribute(path, "/material", "poisson_ratio");
  set_int_attribute(path, "/material", "poisson_ratio", 1);
  expect_read_error(path, {"nu.fbh5: /material/poisson_ratio is 1, expected -1 < nu < 0.5"});
}

// element_order says how many nodes each row of /mesh/tets has (SCHEMA.md, Mesh): a linear file whose attribute claims
// quadratic elements is refused by the dataset's shape, and an order the format does not know by name.
TEST_F(ReadErrors, ElementOrderMustMatchTheTetsColumns) {
  const auto path = good_file("order.fbh5");
  set_int_attribute(path, "/mesh", "element_order", 2);
  expect_read_error(path, {"/mesh/tets has shape 2 x 4, expected n_e (element_order 2) x 10"});
  set_int_attribute(path, "/mesh", "element_order", 3);
  expect_read_error(path, {"/mesh/element_order is 3, expected 1 (linear 4-node tetrahedra) or 2"});
}

TEST_F(ReadErrors, MissingGcmsMatrix) {
  const auto path = good_file("no_g.fbh5");
  delete_link(path, "/gcms/G");
  expect_read_error(path, {"no_g.fbh5: missing dataset /gcms/G"});
}

TEST_F(ReadErrors, WrongStiffnessShape) {
  const auto path = good_file("k_shape.fbh5");
  replace_double_dataset(path, "/gcms/K_hat", 12, 12, std::vector<double>(144, 1.0));
  expect_read_error(path, {"k_shape.fbh5: /gcms/K_hat has shape 12 x 12, expected 15 x 15 (3 n_f square)"});
}

TEST_F(ReadErrors, AsymmetricStiffness) {
  const auto path = good_file("k_asym.fbh5");
  std::vector<double> k(15 * 15, 0.0);
  for (int i = 0; i < 15; ++i) k[i * 15 + i] = 1.0;
  k[0 * 15 + 1] = 0.5;  // K̂[0][1] without K̂[1][0]
  replace_double_dataset(path, "/gcms/K_hat", 15, 15, k);
  expect_read_error(path, {"k_asym.fbh5: /gcms/K_hat is not symmetric: /gcms/K_hat[0][1] = 0.5 but /gcms/K_hat[1][0] = 0"});
}

TEST_F(ReadErrors, MassMatrixThatIsNotPositiveDefinite) {
  const auto path = good_file("g_indef.fbh5");
  BodyData body = make_body();
  Eigen::MatrixXd g = body.gcms.mass_matrix;
  g(1, 4) = g(4, 1) = 1.0;  // a field coupled to the x-rotation more strongly than J allows: J - T Tᵀ < 0
  std::vector<double> values(g.data(), g.data() + g.size());  // symmetric: column- = row-major
  replace_double_dataset(path, "/gcms/G", 9, 9, values);
  expect_read_error(path, {"g_indef.fbh5: /gcms/G is not positive definite"});
}

TEST_F(ReadErrors, MassMatrixThatContradictsTheMass) {
  const auto path = good_file("g_mass.fbh5");
  BodyData body = make_body();
  Eigen::MatrixXd g = body.gcms.mass_matrix;
  g(0, 0) *= 2.0;
  std::vector<double> values(g.data(), g.data() + g.size());
  replace_double_dataset(path, "/gcms/G", 9, 9, values);
  expect_read_error(path, {"g_mass.fbh5: /gcms/G[0][0] = ", "differs from /mass/total"});
}

TEST_F(ReadErrors, FieldModeStoredAsAMatrix) {
  const auto path = good_file("field_mode.fbh5");
  replace_int_dataset(path, "/gcms/field_mode", 5, 1, {0, 1, 0, 1, 1});
  expect_read_error(path, {"field_mode.fbh5: /gcms/field_mode has shape 5 x 1, expected a 1-D dataset"});
}

TEST_F(ReadErrors, InterfaceListedButMissing) {
  const auto path = good_file("no_interface.fbh5");
  set_string_attribute(path, "/interfaces", "order", "bore A,bore B");
  expect_read_error(path, {"no_interface.fbh5: /interfaces/order names \"bore B\" but there is no group /interfaces/bore B"});
}

TEST_F(ReadErrors, InterfaceWithoutWeights) {
  const auto path = good_file("no_weights.fbh5");
  delete_link(path, "/interfaces/bore A/weights");
  expect_read_error(path, {"no_weights.fbh5: missing dataset /interfaces/bore A/weights"});
}

TEST_F(ReadErrors, FixedInterfaceFrequenciesAreOptional) {
  // Written by every fbprep since Craig-Bampton; absent in earlier version-2 files, which stay readable.
  const auto path = good_file("no_fixed.fbh5");
  delete_link(path, "/reduction/fixed_interface_frequencies_hz");
  EXPECT_EQ(read_edited(path).modes.fixed_interface_frequencies_hz.size(), 0);
}

TEST_F(ReadErrors, DeclaredUnitIsOptional) {
  // Added with the unit override (issue 12); files written before it stay readable, with no declared unit.
  const auto path = good_file("no_declared_unit.fbh5");
  EXPECT_EQ(read_edited(path).provenance.declared_unit, "mm");
  delete_attribute(path, "/", "declared_unit");
  EXPECT_EQ(read_edited(path).provenance.declared_unit, "");
}

TEST_F(ReadErrors, ScaledConditionBeforeIsOptional) {
  // Written by fbprep since issue 12; absent in earlier version-3 files, which stay readable.
  const auto path = good_file("no_scaled_before.fbh5");
  delete_attribute(path, "/gcms", "condition_G_scaled_before");
  EXPECT_FALSE(read_edited(path).gcms.condition_mass_scaled_before.has_value());
}

TEST_F(ReadErrors, TruncatedFile) {
  const auto good = good_file("whole.fbh5");
  const std::string bytes = read_bytes(good);
  const auto path = dir() / "half.fbh5";
  write_bytes(path, bytes.substr(0, bytes.size() / 2));
  expect_read_error(path, {"half.fbh5: ", "truncated"});
}

TEST_F(ReadErrors, EveryTruncationIsRefusedWithoutCrashing) {
  const auto good = good_file("whole.fbh5");
  const std::string bytes = read_bytes(good);
  const auto path = dir() / "cut.fbh5";
  for (std::size_t size = 0; size < bytes.size(); size += std::max<std::size_t>(1, bytes.size() / 97)) {
    write_bytes(path, bytes.substr(0, size));
    expect_read_error(path, {"cut.fbh5: "});
  }
}

}  // namespace
}  // namespace flexbody::format::test
