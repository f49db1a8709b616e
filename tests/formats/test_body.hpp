#pragma once
// test_body.hpp: fixtures for the format tests: a small synthetic body, a per-test temporary
// directory, an expectation on BodyFileError messages, and HDF5 surgery to build bad files.

#include "flexbody/format/body_data.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace flexbody::format::test {

/// Two linear tetrahedra sharing a face (5 nodes, 6 surface triangles) with 2 modes; every value
/// is distinct and not exactly representable in few digits, so a round trip must be bit-exact.
[[nodiscard]] BodyData make_body();

/// Mode m's shape in the fields, ξ̄_f = C(f, 3m..3m+2) (3 n_f).
[[nodiscard]] Eigen::VectorXd mode_shape(const Gcms& gcms, Eigen::Index m);
/// Sets each stored frequency to its mode's Rayleigh quotient in K̂, c_mᵀ K̂ c_m = ω_m², as the reader checks.
void match_frequencies_to_stiffness(BodyData& body);

/// `body` made `scale` times as large in every length, of the same material: lengths x s, mass x s^3,
/// inertia x s^5, frequencies / s, and each quantity whose unit holds kg or m accordingly (the fields, kg^-1/2,
/// x s^-3/2; K̂ x s^-2; G's rows of τ, a, ξ x s^3/2, s^5/2, 1). The unit-free figures stay as they are; the
/// two condition numbers of G in SI units become +inf, which is what a writer that computes them without
/// scaling finds for a small part.
[[nodiscard]] BodyData scaled_body(const BodyData& body, double scale);

/// A fresh directory under temp_directory_path(), removed after the test.
class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override;
  void TearDown() override;
  [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }
  /// Names of every entry of dir(), sorted.
  [[nodiscard]] std::vector<std::string> entries() const;

 private:
  std::filesystem::path dir_;
};

/// Runs `action`, expecting a BodyFileError whose message contains every one of `parts`.
void expect_body_file_error(const std::function<void()>& action, const std::vector<std::string>& parts);

/// The bytes of a file.
[[nodiscard]] std::string read_bytes(const std::filesystem::path& path);
/// Writes `bytes` to a new file.
void write_bytes(const std::filesystem::path& path, const std::string& bytes);

// Surgery on an existing file with the HDF5 C API; each fails the test on an HDF5 error.
/// Replaces (or adds) the string attribute `name` of the object `object`; variable-length (as h5py
/// writes a str) or fixed-length, NUL-padded (as h5py writes numpy bytes).
void set_string_attribute(const std::filesystem::path& file, const std::string& object, const std::string& name,
                          const std::string& value, bool fixed_length = false);
/// Replaces (or adds) the int attribute `name` of the object `object`.
void set_int_attribute(const std::filesystem::path& file, const std::string& object, const std::string& name,
                       int value);
/// Removes the attribute `name` of the object `object`.
void delete_attribute(const std::filesystem::path& file, const std::string& object, const std::string& name);
/// Removes the link (group or dataset) `path`.
void delete_link(const std::filesystem::path& file, const std::string& path);
/// Replaces the dataset `path` by a rows x cols double dataset with row-major `values`.
void replace_double_dataset(const std::filesystem::path& file, const std::string& path, std::size_t rows,
                            std::size_t cols, const std::vector<double>& values);
/// Replaces the dataset `path` by a rows x cols double dataset that is declared but never written (HDF5 allocates
/// no storage for it: a huge shape in a small file).
void declare_double_dataset(const std::filesystem::path& file, const std::string& path, std::size_t rows,
                            std::size_t cols);
/// Replaces the dataset `path` by a rows x cols int32 dataset with row-major `values`.
void replace_int_dataset(const std::filesystem::path& file, const std::string& path, std::size_t rows,
                         std::size_t cols, const std::vector<int>& values);
/// A dataset as stored: its shape and its values in storage (row-major) order.
struct RawDataset {
  std::vector<unsigned long long> shape;
  std::vector<double> values;
};
/// Reads the floating-point dataset `path` as stored, without the library under test.
[[nodiscard]] RawDataset read_raw_dataset(const std::filesystem::path& file, const std::string& path);
/// Reads the string attribute `name` of the object `object`, without the library under test, expecting the
/// type the writer uses (fixed-length, NUL-padded, UTF-8).
[[nodiscard]] std::string read_raw_string_attribute(const std::filesystem::path& file, const std::string& object,
                                                    const std::string& name);

}  // namespace flexbody::format::test
