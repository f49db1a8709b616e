// body_file_roundtrip_test.cpp: write then read gives back every field exactly; the layout on disk
// is the one of SCHEMA.md; writes are atomic.
#include "test_body.hpp"

#include "flexbody/format/body_file.hpp"

#include <gtest/gtest.h>

namespace flexbody::format::test {
namespace {

void expect_same(const BodyData& a, const BodyData& b) {
  EXPECT_EQ(a.provenance.created_by, b.provenance.created_by);
  EXPECT_EQ(a.provenance.created_utc, b.provenance.created_utc);
  EXPECT_EQ(a.provenance.source_file, b.provenance.source_file);
  EXPECT_EQ(a.provenance.source_sha256, b.provenance.source_sha256);
  EXPECT_EQ(a.provenance.input_unit, b.provenance.input_unit);
  EXPECT_EQ(a.provenance.unit_reason, b.provenance.unit_reason);
  EXPECT_EQ(a.provenance.declared_unit, b.provenance.declared_unit);
  EXPECT_EQ(a.provenance.options, b.provenance.options);

  EXPECT_EQ(a.material.name, b.material.name);
  EXPECT_EQ(a.material.youngs_modulus, b.material.youngs_modulus);
  EXPECT_EQ(a.material.poisson_ratio, b.material.poisson_ratio);
  EXPECT_EQ(a.material.density, b.material.density);

  EXPECT_EQ(a.mass.mass, b.mass.mass);
  EXPECT_EQ(a.mass.center_of_mass_input, b.mass.center_of_mass_input);
  EXPECT_EQ(a.mass.inertia_about_com, b.mass.inertia_about_com);

  ASSERT_EQ(a.mesh.nodes.rows(), b.mesh.nodes.rows());
  EXPECT_EQ(a.mesh.nodes, b.mesh.nodes);
  ASSERT_EQ(a.mesh.tets.rows(), b.mesh.tets.rows());
  EXPECT_EQ(a.mesh.tets, b.mesh.tets);
  ASSERT_EQ(a.mesh.surface_triangles.rows(), b.mesh.surface_triangles.rows());
  EXPECT_EQ(a.mesh.surface_triangles, b.mesh.surface_triangles);
  EXPECT_EQ(a.mesh.element_order, b.mesh.element_order);

  EXPECT_EQ(a.modes.kind, b.modes.kind);
  EXPECT_EQ(a.modes.eigensolver, b.modes.eigensolver);
  EXPECT_EQ(a.modes.shift, b.modes.shift);
  ASSERT_EQ(a.modes.frequencies_hz.size(), b.modes.frequencies_hz.size());
  EXPECT_EQ(a.modes.frequencies_hz, b.modes.frequencies_hz);
  ASSERT_EQ(a.modes.relative_residuals.size(), b.modes.relative_residuals.size());
  EXPECT_EQ(a.modes.relative_residuals, b.modes.relative_residuals);
  EXPECT_EQ(a.modes.fixed_interface_frequencies_hz, b.modes.fixed_interface_frequencies_hz);
  ASSERT_EQ(a.modes.upsilon.rows(), b.modes.upsilon.rows());
  ASSERT_EQ(a.modes.upsilon.cols(), b.modes.upsilon.cols());
  EXPECT_EQ(a.modes.upsilon, b.modes.upsilon);

  const Gcms &ga = a.gcms, &gb = b.gcms;
  ASSERT_EQ(ga.fields.cols(), gb.fields.cols());
  EXPECT_EQ(ga.fields, gb.fields);
  EXPECT_EQ(ga.field_mode, gb.field_mode);
  EXPECT_EQ(ga.mode_coefficients, gb.mode_coefficients);
  EXPECT_EQ(ga.mass_matrix, gb.mass_matrix);
  EXPECT_EQ(ga.stiffness, gb.stiffness);
  EXPECT_EQ(ga.drop_tolerance, gb.drop_tolerance);
  EXPECT_EQ(ga.condition_mode_gram_before, gb.condition_mode_gram_before);
  EXPECT_EQ(ga.condition_mass_before, gb.condition_mass_before);
  EXPECT_EQ(ga.condition_mass_after, gb.condition_mass_after);
  EXPECT_EQ(ga.condition_mass_scaled_before, gb.condition_mass_scaled_before);
  EXPECT_EQ(ga.condition_mass_scaled_after, gb.condition_mass_scaled_after);

  ASSERT_EQ(a.interfaces.size(), b.interfaces.size());
  for (std::size_t k = 0; k < a.interfaces.size(); ++k) {
    const Interface &ia = a.interfaces[k], &ib = b.interfaces[k];
    EXPECT_EQ(ia.name, ib.name);
    EXPECT_EQ(ia.coupling, ib.coupling);
    EXPECT_EQ(ia.nodes, ib.nodes);
    EXPECT_EQ(ia.weights, ib.weights);
    EXPECT_EQ(ia.reference_point, ib.reference_point);
    EXPECT_EQ(ia.y_row, ib.y_row);
    EXPECT_EQ(ia.rotation, ib.rotation);
  }
  EXPECT_EQ(a.modes.static_loads, b.modes.static_loads);
  EXPECT_EQ(a.modes.static_correction_modes, b.modes.static_correction_modes);
  ASSERT_EQ(a.recovery.size(), b.recovery.size());
  for (std::size_t k = 0; k < a.recovery.size(); ++k) {
    EXPECT_EQ(a.recovery[k].name, b.recovery[k].name);
    EXPECT_EQ(a.recovery[k].nodes, b.recovery[k].nodes);
    EXPECT_EQ(a.recovery[k].stress_modes, b.recovery[k].stress_modes);
  }
  EXPECT_EQ(a.geometric_stiffness.cases, b.geometric_stiffness.cases);
  ASSERT_EQ(a.geometric_stiffness.matrices.size(), b.geometric_stiffness.matrices.size());
  for (std::size_t k = 0; k < a.geometric_stiffness.matrices.size(); ++k)
    EXPECT_EQ(a.geometric_stiffness.matrices[k], b.geometric_stiffness.matrices[k]);
}

using RoundTrip = TempDirTest;

TEST_F(RoundTrip, KeepsEveryFieldExactly) {
  const BodyData body = make_body();
  const auto path = dir() / "two_tets.fbh5";
  write_body_file(body, path);
  expect_same(body, read_body_file(path));
}

TEST_F(RoundTrip, KeepsEmptyOptionsTrianglesAndModes) {
  BodyData body = make_body();
  body.provenance.options.clear();
  body.mesh.surface_triangles.resize(0, 3);
  body.modes.frequencies_hz.resize(0);
  body.modes.relative_residuals.resize(0);
  body.modes.upsilon.resize(5, 0);
  body.gcms.fields.resize(5, 0);
  body.gcms.field_mode.resize(0);
  body.gcms.mode_coefficients.resize(0, 0);
  body.gcms.mass_matrix = Eigen::MatrixXd(body.gcms.mass_matrix.topLeftCorner(4, 4));  // rigid: [1, X̄] only
  body.gcms.stiffness.resize(0, 0);
  body.interfaces.clear();
  body.recovery.clear();
  body.modes.static_loads.clear();
  body.modes.static_correction_modes = 0;
  body.geometric_stiffness = {};  // optional: absent from the file, empty when read
  const auto path = dir() / "bare.fbh5";
  write_body_file(body, path);
  expect_same(body, read_body_file(path));
}

// A 1 mm and a 1 km body (issue 12): written, read back with every check of the reader, unchanged.
TEST_F(RoundTrip, TinyAndHugeBodiesReadBack) {
  for (const double s : {2e-2, 2e4}) {
    SCOPED_TRACE(s);
    const BodyData body = scaled_body(make_body(), s);
    const auto path = dir() / "scaled.fbh5";
    write_body_file(body, path);
    expect_same(body, read_body_file(path));
  }
}

TEST_F(RoundTrip, StoresUpsilonRowMajorInListFormat) {
  const BodyData body = make_body();
  const auto path = dir() / "layout.fbh5";
  write_body_file(body, path);

  const RawDataset upsilon = read_raw_dataset(path, "/reduction/upsilon");
  ASSERT_EQ(upsilon.shape, (std::vector<unsigned long long>{5, 6}));
  // Element [i][3m+k]: component k of mode m at node i, stored row after row.
  for (Eigen::Index i = 0; i < 5; ++i) {
    for (Eigen::Index m = 0; m < 2; ++m) {
      for (Eigen::Index k = 0; k < 3; ++k) {
        const auto flat = static_cast<std::size_t>(i * 6 + 3 * m + k);
        EXPECT_EQ(upsilon.values[flat], body.modes.upsilon(i, 3 * m + k)) << "node " << i << " mode " << m;
      }
    }
  }
  const RawDataset nodes = read_raw_dataset(path, "/mesh/nodes");
  ASSERT_EQ(nodes.shape, (std::vector<unsigned long long>{5, 3}));
  EXPECT_EQ(nodes.values[3 * 4 + 1], body.mesh.nodes(4, 1));
  const RawDataset inertia = read_raw_dataset(path, "/mass/inertia_about_com");
  EXPECT_EQ(inertia.values[1 * 3 + 2], body.mass.inertia_about_com(1, 2));

  EXPECT_EQ(read_raw_string_attribute(path, "/", "format"), "flexbody");
  EXPECT_EQ(read_raw_string_attribute(path, "/", "length_unit"), "m");
  EXPECT_EQ(read_raw_string_attribute(path, "/provenance/options", "order"), "unit,modes,mesh-size,note");
  EXPECT_EQ(read_raw_string_attribute(path, "/reduction/upsilon", "unit"), "kg^-1/2");
  EXPECT_EQ(read_raw_string_attribute(path, "/reduction/frequencies_hz", "unit"), "Hz");
  EXPECT_EQ(read_raw_string_attribute(path, "/mass/inertia_about_com", "unit"), "kg m^2");
}

using AtomicWrite = TempDirTest;

TEST_F(AtomicWrite, LeavesOnlyTheTarget) {
  write_body_file(make_body(), dir() / "a.fbh5");
  write_body_file(make_body(), dir() / "a.fbh5");  // replaces an existing file
  EXPECT_EQ(entries(), std::vector<std::string>{"a.fbh5"});
}

TEST_F(AtomicWrite, InvalidBodyLeavesExistingTargetUntouched) {
  const auto path = dir() / "keep.fbh5";
  write_body_file(make_body(), path);
  const std::string before = read_bytes(path);

  BodyData bad = make_body();
  bad.mesh.tets(1, 2) = 57;
  expect_body_file_error([&] { write_body_file(bad, path); },
                         {"body data: /mesh/tets[1] refers to node 57 but the mesh has 5 nodes"});
  EXPECT_EQ(read_bytes(path), before);
  EXPECT_EQ(entries(), std::vector<std::string>{"keep.fbh5"});
}

TEST_F(AtomicWrite, FailedRenameRemovesTheTemporary) {
  // The target is a directory: the temporary is written completely, then cannot replace it.
  const auto path = dir() / "taken.fbh5";
  std::filesystem::create_directory(path);
  std::filesystem::create_directory(path / "inside");
  expect_body_file_error([&] { write_body_file(make_body(), path); }, {path.string(), "cannot move"});
  EXPECT_EQ(entries(), std::vector<std::string>{"taken.fbh5"});
  EXPECT_TRUE(std::filesystem::is_directory(path / "inside"));
}

TEST_F(AtomicWrite, MissingDirectoryIsReported) {
  const auto path = dir() / "no" / "such" / "dir.fbh5";
  expect_body_file_error([&] { write_body_file(make_body(), path); }, {path.string(), "cannot create"});
  EXPECT_TRUE(entries().empty());
}

}  // namespace
}  // namespace flexbody::format::test
