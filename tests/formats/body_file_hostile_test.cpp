// body_file_hostile_test.cpp: files made to hurt the reader, not merely damaged (issue 13): paths that are not
// regular files, HDF5 features a body file never uses (links other than hard ones, chunked, filtered or external
// storage, variable-length strings in a sealed file), integers beyond 32 bits, and mode coefficients that no
// M-orthonormal modes have. Each is refused with one line naming the file and the item, and none waits or reads
// another file. A seal is no signature (anyone can compute one), so most of these are sealed after the edit.
#include "test_body.hpp"

#include "body_file_seal.hpp"
#include "hdf5_structure.hpp"

#include "flexbody/format/body_file.hpp"

#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <array>
#include <utility>
#include <cstdint>
#include <string>
#include <vector>

namespace flexbody::format::test {
namespace {

/// An HDF5 identifier closed at scope exit; fails the test if HDF5 could not create it.
class Hdf5 {
 public:
  Hdf5(hid_t id, herr_t (*closer)(hid_t)) : id_(id), closer_(closer) { EXPECT_GE(id, 0); }
  ~Hdf5() {
    if (id_ >= 0) closer_(id_);
  }
  Hdf5(const Hdf5&) = delete;
  Hdf5& operator=(const Hdf5&) = delete;
  [[nodiscard]] hid_t get() const { return id_; }

 private:
  hid_t id_;
  herr_t (*closer_)(hid_t);
};

class Hostile : public TempDirTest {
 protected:
  std::filesystem::path good_file(const std::string& name) {
    const auto path = dir() / name;
    write_body_file(make_body(), path);
    return path;
  }

  /// Seals an edited file again, as `fbprep seal` would if it accepted it (or as anyone can: a seal is a digest).
  static void reseal(const std::filesystem::path& path) { detail::write_seal(path, path.string()); }

  /// Expects the default (sealed) read of `path` to throw a one-line message that starts with the path and holds
  /// every one of `parts`.
  static void expect_refused(const std::filesystem::path& path, std::initializer_list<std::string> parts) {
    std::vector<std::string> expected{path.string() + ": "};
    expected.insert(expected.end(), parts);
    expect_body_file_error([&] { (void)read_body_file(path); }, expected);
  }

  /// Replaces /gcms/G by a copy stored with the dataset creation properties `creation` (same values).
  static void restore_g_with(const std::filesystem::path& path, hid_t creation) {
    const RawDataset g = read_raw_dataset(path, "/gcms/G");
    const Hdf5 file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose);
    ASSERT_GE(H5Ldelete(file.get(), "/gcms/G", H5P_DEFAULT), 0);
    const std::array<hsize_t, 2> dims{g.shape[0], g.shape[1]};
    const Hdf5 space(H5Screate_simple(2, dims.data(), nullptr), H5Sclose);
    const Hdf5 dataset(H5Dcreate2(file.get(), "/gcms/G", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, creation, H5P_DEFAULT),
                       H5Dclose);
    ASSERT_GE(H5Dwrite(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, g.values.data()), 0);
  }
};

TEST_F(Hostile, AFifoIsRefusedWithoutWaitingForAWriter) {
  const auto path = dir() / "pipe.fbh5";
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  expect_refused(path, {"is a FIFO (named pipe), not a body file"});  // before: open() waited for a writer forever
}

TEST_F(Hostile, ADeviceIsRefused) { expect_refused("/dev/zero", {"is a device, not a body file"}); }

TEST_F(Hostile, AnUnreadableFileSaysWhy) {
  if (::geteuid() == 0) GTEST_SKIP() << "root reads every file; permissions cannot be tested";
  const auto path = good_file("locked.fbh5");
  std::filesystem::permissions(path, std::filesystem::perms::none);
  expect_refused(path, {"cannot be opened for reading: Permission denied"});
}

TEST_F(Hostile, VariableLengthStringsInASealedFileAreRefused) {
  // h5py writes a str attribute variable-length, into the global heap whose damage crashed libhdf5; a sealed file
  // never holds one, because `fbprep seal` rewrites the file with fixed-length strings.
  const auto path = good_file("vlen.fbh5");
  set_string_attribute(path, "/material", "name", "aluminium");
  reseal(path);
  expect_refused(path, {"/material/name is a variable-length string"});
  // What `fbprep seal` reads (the seal not required) is still accepted and checked.
  EXPECT_EQ(read_body_file(path, ReadOptions{.require_seal = false}).material.name, "aluminium");
}

TEST_F(Hostile, SoftExternalAndLoopingLinksAreRefused) {
  struct Case {
    const char* name;
    std::function<herr_t(hid_t)> link;
    const char* problem;
  };
  const std::vector<Case> cases = {
      {"soft.fbh5", [](hid_t f) { return H5Lcreate_soft("/gcms/G", f, "/extra", H5P_DEFAULT, H5P_DEFAULT); },
       "/extra is a soft link; a body file holds hard links only"},
      {"loop.fbh5", [](hid_t f) { return H5Lcreate_soft("/gcms/loop", f, "/gcms/loop", H5P_DEFAULT, H5P_DEFAULT); },
       "/gcms/loop is a soft link"},
      {"external.fbh5",
       [](hid_t f) { return H5Lcreate_external("/dev/zero", "/", f, "/reduction/elsewhere", H5P_DEFAULT, H5P_DEFAULT); },
       "/reduction/elsewhere is an external link"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const auto path = good_file(c.name);
    {
      const Hdf5 file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose);
      ASSERT_GE(c.link(file.get()), 0);
    }
    reseal(path);
    expect_refused(path, {c.problem});  // from the bytes
    // ... and by libhdf5's link walk when the seal is not required (fbprep seal), before any link is followed.
    expect_body_file_error([&] { (void)read_body_file(path, ReadOptions{.require_seal = false}); }, {c.problem});
  }
}

TEST_F(Hostile, ChunkedFilteredAndExternalDatasetsAreRefused) {
  const std::array<hsize_t, 2> chunk{3, 3};
  {
    const auto path = good_file("chunked.fbh5");
    const Hdf5 creation(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    ASSERT_GE(H5Pset_chunk(creation.get(), 2, chunk.data()), 0);
    restore_g_with(path, creation.get());
    reseal(path);
    expect_refused(path, {"/gcms/G has a data layout fbprep never writes (only contiguous storage)"});
    expect_body_file_error([&] { (void)read_body_file(path, ReadOptions{.require_seal = false}); },
                           {"/gcms/G is stored in chunks; a body file's datasets are contiguous"});
  }
  {
    const auto path = good_file("deflated.fbh5");
    const Hdf5 creation(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    ASSERT_GE(H5Pset_chunk(creation.get(), 2, chunk.data()), 0);
    ASSERT_GE(H5Pset_deflate(creation.get(), 6), 0);
    restore_g_with(path, creation.get());
    reseal(path);
    // Refused from the bytes, before libhdf5 decodes the pipeline; read without the seal, by the dataset's layout.
    expect_refused(path, {"/gcms/G holds an HDF5 message of type 11 (a filter pipeline: compression)"});
    expect_body_file_error([&] { (void)read_body_file(path, ReadOptions{.require_seal = false}); },
                           {"/gcms/G is stored in chunks"});
  }
  {
    // External storage: the values of /gcms/G would be read from another file, here one beside the body file that
    // holds them; the refusal comes before any read of it.
    const auto path = good_file("external.fbh5");
    const auto values = dir() / "g.raw";
    write_bytes(values, std::string(8 * 81, '\0'));
    const Hdf5 creation(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    ASSERT_GE(H5Pset_external(creation.get(), values.c_str(), 0, 8 * 81), 0);
    restore_g_with(path, creation.get());
    reseal(path);
    expect_refused(path, {"/gcms/G holds an HDF5 message of type 7 (external storage)"});
    expect_body_file_error([&] { (void)read_body_file(path, ReadOptions{.require_seal = false}); },
                           {"/gcms/G keeps its values in external files"});
  }
}

TEST_F(Hostile, AFormatVersionBeyond32BitsIsReportedAsItIs) {
  const auto path = good_file("version64.fbh5");
  {
    const Hdf5 file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose);
    ASSERT_GE(H5Adelete(file.get(), "format_version"), 0);
    const Hdf5 space(H5Screate(H5S_SCALAR), H5Sclose);
    const Hdf5 attribute(H5Acreate2(file.get(), "format_version", H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                         H5Aclose);
    const std::int64_t version = (std::int64_t{1} << 32) + 4;  // before: HDF5 clamped it, "format_version 2147483647"
    ASSERT_GE(H5Awrite(attribute.get(), H5T_NATIVE_INT64, &version), 0);
  }
  reseal(path);
  expect_refused(path, {"/format_version is 4294967300, beyond the range of a 32-bit integer"});
}

TEST_F(Hostile, ModeCoefficientsOfNoOrthonormalModesAreRefused) {
  // A finite, plausible-looking C that no M-orthonormal modes give (its mode-0 columns doubled): before, accepted.
  const auto path = good_file("coefficients.fbh5");
  RawDataset c = read_raw_dataset(path, "/gcms/mode_coefficients");
  for (std::size_t f = 0; f < c.shape[0]; ++f)
    for (std::size_t j = 0; j < 3; ++j) c.values[f * c.shape[1] + j] *= 2.0;
  replace_double_dataset(path, "/gcms/mode_coefficients", c.shape[0], c.shape[1], c.values);
  reseal(path);
  expect_refused(path, {"/gcms/mode_coefficients: the squares of columns 0 to 2 (mode 0) sum to ", "expected 1"});
}

TEST_F(Hostile, ManyInterfacesAndOptionsStayInTheirObjectHeaders) {
  // HDF5 moves a group's links and attributes into a fractal heap and B-tree beyond 8 by default; the writer keeps
  // them in the object header, which is all a sealed file may use (hdf5_structure.hpp). 12 interfaces, 20 options.
  BodyData body = make_body();
  for (int k = 1; k < 12; ++k) {
    Interface copy = body.interfaces.front();
    copy.name = "bore " + std::to_string(k);
    body.interfaces.push_back(copy);
  }
  for (int k = 0; k < 16; ++k) body.provenance.options.emplace_back("option" + std::to_string(k), std::to_string(k));
  const auto path = dir() / "many.fbh5";
  write_body_file(body, path);
  EXPECT_EQ(detail::check_hdf5_structure(read_bytes(path), detail::kSealBytes), "");  // HDF5's defaults fail this
  const BodyData read = read_body_file(path);
  EXPECT_EQ(read.interfaces.size(), 12u);
  EXPECT_EQ(read.provenance.options.size(), 20u);
}

TEST_F(Hostile, DenseAttributeStorageIsRefusedBeforeHdf5FollowsIt) {
  // What HDF5 writes by default for a group with 9 attributes: a fractal heap and a B-tree, whose changed addresses
  // crashed libhdf5 1.10 in issue 13's fuzz run (22 of 1,000 files with HDF5's checksums and the seal recomputed).
  const auto path = good_file("dense.fbh5");
  {
    const Hdf5 file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose);
    const Hdf5 group(H5Gcreate2(file.get(), "/extra", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    const Hdf5 space(H5Screate(H5S_SCALAR), H5Sclose);
    for (int k = 0; k < 9; ++k) {
      std::string name = "a";  // not "a" + to_string(k): GCC 12's -Wrestrict misfires on it at -O3
      name += std::to_string(k);
      const Hdf5 attribute(H5Acreate2(group.get(), name.c_str(), H5T_STD_I32LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                           H5Aclose);
      ASSERT_GE(H5Awrite(attribute.get(), H5T_NATIVE_INT, &k), 0);
    }
  }
  reseal(path);
  expect_refused(path, {"its HDF5 structure is not what fbprep writes (/extra stores its attributes densely (a heap "
                        "or B-tree at "});
  // `fbprep seal` (the seal not required) still reads it and writes it again in the compact form.
  write_body_file(read_body_file(path, ReadOptions{.require_seal = false}), path);
  EXPECT_EQ(read_body_file(path).material.name, make_body().material.name);
}

TEST_F(Hostile, FilesThatCrashedLibhdf5AreRefusedFromTheirBytes) {
  // tests/data/hostile/README.md: sealed, with HDF5's checksums recomputed; each crashed both tools or had libhdf5
  // follow an unchecked address until the reader checked the structure itself.
  const std::filesystem::path data = std::filesystem::path(FLEXBODY_TEST_DATA_DIR) / "hostile";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"vds1.fbh5", "/gcms/G has a data layout fbprep never writes (only contiguous storage)"},
      {"vlfill.fbh5", "/gcms/G is a variable-length string (or sequence)"},
      {"sh_self.fbh5", "/gcms/G holds a message of type 3 with flags fbprep never sets"},
      {"sh_other.fbh5", "/gcms/G holds a message of type 3 with flags fbprep never sets"},
      {"fillsize.fbh5", "/gcms/G has a fill value message fbprep never writes"},
      {"v2000.fbh5", "/n/n/n/n/n/n/n/n/n lies deeper than 8 groups"},
  };
  for (const auto& [name, problem] : cases) {
    SCOPED_TRACE(name);
    expect_refused(data / name, {"its HDF5 structure is not what fbprep writes (" + problem});
  }
}

}  // namespace
}  // namespace flexbody::format::test
