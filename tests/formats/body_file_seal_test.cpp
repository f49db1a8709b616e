// body_file_seal_test.cpp: written files are sealed and hold no HDF5 global heap; the reader refuses a file
// whose bytes changed after it was written before HDF5 parses it; version-3 files stay readable.
#include "test_body.hpp"

#include "body_file_seal.hpp"
#include "sha256.hpp"

#include "flexbody/format/body_file.hpp"

#include <hdf5.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace flexbody::format::test {
namespace {

constexpr std::size_t kSeal = detail::kSealBytes;
const std::string kHdf5Signature("\x89HDF\r\n\x1a\n", 8);

std::string sha256_hex(std::string_view bytes) {
  detail::Sha256 hash;
  hash.update({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()});
  return detail::to_hex(hash.finish());
}

herr_t count_variable_length_string(hid_t object, const char* name, const H5A_info_t* /*info*/, void* count) {
  const hid_t attribute = H5Aopen(object, name, H5P_DEFAULT);
  const hid_t type = H5Aget_type(attribute);
  if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) > 0) ++*static_cast<int*>(count);
  H5Tclose(type);
  H5Aclose(attribute);
  return 0;
}

herr_t count_in_object(hid_t root, const char* name, const H5O_info_t* /*info*/, void* count) {
  const hid_t object = H5Oopen(root, name, H5P_DEFAULT);
  H5Aiterate2(object, H5_INDEX_NAME, H5_ITER_NATIVE, nullptr, count_variable_length_string, count);
  H5Oclose(object);
  return 0;
}

/// The number of variable-length string attributes (whose values live in the global heap) in the file.
int variable_length_string_attributes(const std::filesystem::path& path) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(file, 0);
  int count = 0;
  H5Ovisit2(file, H5_INDEX_NAME, H5_ITER_NATIVE, count_in_object, &count, H5O_INFO_BASIC);  // the root too
  H5Fclose(file);
  return count;
}

class Seal : public TempDirTest {
 protected:
  std::filesystem::path sealed_file(const std::string& name) {
    const auto path = dir() / name;
    write_body_file(make_body(), path);
    return path;
  }

  /// A copy of `good` with `bytes` as its content, and the test's expectation that reading it is refused
  /// as damaged: one line, naming the file, saying what to do about an intended edit, and containing `problem`.
  void expect_damaged(const std::string& name, const std::string& bytes, const std::string& problem) {
    SCOPED_TRACE(name);
    const auto path = dir() / name;
    write_bytes(path, bytes);
    try {
      (void)read_body_file(path);
      ADD_FAILURE() << "read without an error";
    } catch (const BodyFileDamaged& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(path.string() + ": damaged or modified after it was written: ", 0), 0u) << message;
      EXPECT_NE(message.find(problem), std::string::npos) << message;
      EXPECT_NE(message.find("; if it was edited on purpose, check and re-seal it with: fbprep seal " + path.string()),
                std::string::npos)
          << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
};

TEST_F(Seal, WrittenFileCarriesTheSealOfItsBytes) {
  const auto path = sealed_file("sealed.fbh5");
  const std::string bytes = read_bytes(path);
  ASSERT_GT(bytes.size(), kSeal);
  const std::string hdf5 = bytes.substr(kSeal);
  // The layout SCHEMA.md documents (and its hashlib snippet checks): four lines, then NUL bytes to 512.
  const std::string text = "flexbody seal 1\nalgorithm sha256\nhdf5_bytes " + std::to_string(hdf5.size()) +
                           "\ndigest " + sha256_hex(hdf5) + "\n";
  EXPECT_EQ(bytes.substr(0, text.size()), text);
  EXPECT_EQ(bytes.substr(text.size(), kSeal - text.size()), std::string(kSeal - text.size(), '\0'));
  EXPECT_EQ(bytes.substr(kSeal, 8), kHdf5Signature);  // the HDF5 superblock right after the user block

  const BodyData read = read_body_file(path);
  EXPECT_TRUE(read.sealed);
  EXPECT_EQ(read.format_version, 4);
  EXPECT_EQ(read.modes.frequencies_hz, make_body().modes.frequencies_hz);  // bit-exact: RoundTrip has the rest
}

TEST_F(Seal, WrittenFileHasNoGlobalHeap) {
  // Every string attribute is fixed-length, so HDF5 writes no global heap collection (signature "GCOL"): the
  // structure every crash and hang of the issue-13 fuzz run went through. make_body() has an empty option
  // value, the case a fixed-length type cannot hold directly.
  const auto path = sealed_file("no_heap.fbh5");
  EXPECT_EQ(read_bytes(path).find("GCOL"), std::string::npos);
  EXPECT_EQ(variable_length_string_attributes(path), 0);
  const BodyData read = read_body_file(path);
  EXPECT_EQ(read.provenance.options, make_body().provenance.options);
}

TEST_F(Seal, FlippedBitAfterTheSealIsRefused) {
  const std::string good = read_bytes(sealed_file("good.fbh5"));
  // The superblock's first byte, one inside it, the middle of the file and its last byte.
  for (const std::size_t at : {kSeal, kSeal + 9, good.size() / 2, good.size() - 1}) {
    std::string bytes = good;
    bytes[at] = static_cast<char>(bytes[at] ^ 0x10);
    expect_damaged("flip_" + std::to_string(at) + ".fbh5", bytes,
                   "the SHA-256 digest of its contents differs from the one its seal records");
  }
}

TEST_F(Seal, DamagedSealIsRefused) {
  const std::string good = read_bytes(sealed_file("good.fbh5"));
  // The magic line, the algorithm line, the padding: a changed byte anywhere in the 512 is damage.
  for (const std::size_t at : {std::size_t{0}, std::size_t{3}, std::size_t{20}, std::size_t{300}, kSeal - 1}) {
    std::string bytes = good;
    bytes[at] = static_cast<char>(bytes[at] ^ 0x01);
    expect_damaged("seal_" + std::to_string(at) + ".fbh5", bytes, "its seal (the first 512 bytes) is damaged");
  }
  // A flipped bit in a digit of hdf5_bytes or of the digest gives another digit (a length or digest mismatch)
  // or none (a damaged seal): refused either way, with one of the problems above.
  for (std::size_t at = 0; at < kSeal && good[at] != '\0'; ++at) {
    if (good[at] == '\n' || good[at] == ' ') continue;
    for (const int bit : {0x01, 0x08, 0x40}) {
      std::string bytes = good;
      bytes[at] = static_cast<char>(bytes[at] ^ bit);
      expect_damaged("seal_" + std::to_string(at) + "_" + std::to_string(bit) + ".fbh5", bytes, "");
    }
  }
  std::string zeroed = good;
  std::fill(zeroed.begin(), zeroed.begin() + 64, '\0');
  expect_damaged("zeroed.fbh5", zeroed, "its seal (the first 512 bytes) is damaged");
}

TEST_F(Seal, TruncatedOrExtendedFileIsRefused) {
  const std::string good = read_bytes(sealed_file("good.fbh5"));
  const std::string hdf5_bytes = std::to_string(good.size() - kSeal);
  expect_damaged("short1.fbh5", good.substr(0, good.size() - 1),
                 "its seal records " + hdf5_bytes + " bytes after the seal, the file has " +
                     std::to_string(good.size() - kSeal - 1) + " (truncated)");
  expect_damaged("half.fbh5", good.substr(0, good.size() / 2), "(truncated)");
  expect_damaged("seal_only.fbh5", good.substr(0, kSeal), "the file has 0 (truncated)");
  expect_damaged("in_seal.fbh5", good.substr(0, 100), "it is truncated to 100 bytes, less than its 512-byte seal");
  expect_damaged("in_magic.fbh5", good.substr(0, 5), "it is truncated to 5 bytes");
  expect_damaged("appended.fbh5", good + '\0', "(bytes appended)");
}

TEST_F(Seal, EditedFileIsRefusedUntilResealed) {
  const auto path = sealed_file("edited.fbh5");
  set_string_attribute(path, "/material", "name", "aluminium");  // what an h5py user does
  expect_body_file_error([&] { (void)read_body_file(path); },
                         {path.string() + ": damaged or modified after it was written: "});

  // Without the seal required the reader runs every other check and says the seal did not match ...
  const BodyData edited = read_body_file(path, ReadOptions{.require_seal = false});
  EXPECT_FALSE(edited.sealed);
  EXPECT_EQ(edited.format_version, 4);
  EXPECT_EQ(edited.material.name, "aluminium");
  // ... and writing it again seals it (what `fbprep seal` does).
  write_body_file(edited, path);
  const BodyData resealed = read_body_file(path);
  EXPECT_TRUE(resealed.sealed);
  EXPECT_EQ(resealed.material.name, "aluminium");
  EXPECT_EQ(read_bytes(path).find("GCOL"), std::string::npos);  // h5py's variable-length string is gone again
}

TEST_F(Seal, Version4WithoutItsSealIsRefused) {
  // The HDF5 part alone (HDF5 finds the superblock at byte 0 then): nothing vouches for it any more.
  const std::string good = read_bytes(sealed_file("good.fbh5"));
  write_bytes(dir() / "stripped.fbh5", good.substr(kSeal));
  expect_body_file_error([&] { (void)read_body_file(dir() / "stripped.fbh5"); },
                         {(dir() / "stripped.fbh5").string() + ": is not sealed ", "fbprep seal "});
  const BodyData read = read_body_file(dir() / "stripped.fbh5", ReadOptions{.require_seal = false});
  EXPECT_FALSE(read.sealed);
}

TEST_F(Seal, Version3FileReadsOnlyWhenTheSealIsNotRequired) {
  // Written by fbprep before files were sealed (tests/data/v3-body/README.md): no seal, variable-length strings.
  const std::filesystem::path v3 = std::filesystem::path(FLEXBODY_TEST_DATA_DIR) / "v3-body" / "beam_v3.fbh5";
  ASSERT_NE(read_bytes(v3).find("GCOL"), std::string::npos);  // so the test reads what it claims to
  // A simulator's read refuses it before HDF5 parses it (its global heap is what crashed libhdf5) ...
  expect_body_file_error([&] { (void)read_body_file(v3); },
                         {v3.string() + ": is not sealed (format version 3", "convert it once with: fbprep seal " + v3.string()});
  // ... and `fbprep seal` reads it with every other check.
  const BodyData body = read_body_file(v3, ReadOptions{.require_seal = false});
  EXPECT_EQ(body.format_version, 3);
  EXPECT_FALSE(body.sealed);
  EXPECT_EQ(body.mesh.nodes.rows(), 110);
  ASSERT_EQ(body.modes.frequencies_hz.size(), 2);
  EXPECT_NEAR(body.modes.frequencies_hz[0], 13056.64, 0.01);  // the README's figure
  EXPECT_EQ(body.interfaces.size(), 1u);

  // Converted: written again, it is a sealed version-4 file with the same content.
  const auto converted = dir() / "beam_v4.fbh5";
  write_body_file(body, converted);
  const BodyData again = read_body_file(converted);
  EXPECT_EQ(again.format_version, 4);
  EXPECT_TRUE(again.sealed);
  EXPECT_EQ(again.modes.upsilon, body.modes.upsilon);
  EXPECT_EQ(again.provenance.options, body.provenance.options);
}

TEST_F(Seal, UnsealedFilesAreNotMistakenForDamagedOnes) {
  // Text that is no seal, and an empty file: no HDF5 signature anywhere, so "not an HDF5 file" as before.
  const auto text = dir() / "text.fbh5";
  write_bytes(text, std::string(600, 'x'));
  expect_body_file_error([&] { (void)read_body_file(text); }, {text.string() + ": not an HDF5 file"});
  const auto empty = dir() / "empty.fbh5";
  write_bytes(empty, "");
  expect_body_file_error([&] { (void)read_body_file(empty); }, {empty.string() + ": not an HDF5 file"});
}

}  // namespace
}  // namespace flexbody::format::test
