// sha256_test.cpp: the seal's SHA-256 against the test vectors of NIST (FIPS 180-2, appendix B; the
// "Example Values" of the Cryptographic Standards and Guidelines: SHA256.pdf), fed whole and in pieces.
#include "sha256.hpp"

#include "flexbody/format/file_digest.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace flexbody::format::detail {
namespace {

std::span<const std::uint8_t> bytes_of(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

std::string hex_of(std::string_view message) {
  Sha256 hash;
  hash.update(bytes_of(message));
  return to_hex(hash.finish());
}

TEST(Sha256, OneBlockMessage) {
  EXPECT_EQ(hex_of("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Sha256, EmptyMessage) {
  EXPECT_EQ(hex_of(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST(Sha256, TwoBlockMessage) {
  // 448 bits: the padding's length field no longer fits the first block.
  EXPECT_EQ(hex_of("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, OneMillionAs) {
  constexpr const char* kExpected = "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0";
  const std::string million(1'000'000, 'a');
  EXPECT_EQ(hex_of(million), kExpected);
  // In pieces of every length from 1 to 129 (in turn), so that the buffering across update() calls is
  // exercised at every offset within a 64-byte block.
  Sha256 hash;
  std::size_t done = 0;
  for (std::size_t piece = 1; done < million.size(); piece = piece % 129 + 1) {
    const std::size_t take = std::min(piece, million.size() - done);
    hash.update(bytes_of(std::string_view(million).substr(done, take)));
    done += take;
  }
  EXPECT_EQ(to_hex(hash.finish()), kExpected);
}

TEST(Sha256, FinishStartsANewMessage) {
  Sha256 hash;
  hash.update(bytes_of("abc"));
  (void)hash.finish();
  EXPECT_EQ(to_hex(hash.finish()), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

// A file's digest (fbprep's provenance) is the same SHA-256, over reads of 64 KiB: one million "a" spans 16 of them.
TEST(Sha256, OfAFile) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "sha256_of_file";
  std::filesystem::create_directories(dir);
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
    return dir / name;
  };
  EXPECT_EQ(sha256_of_file(write("abc", "abc")), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_of_file(write("empty", "")), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_of_file(write("million", std::string(1'000'000, 'a'))),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  // 65 536 bytes exactly: the last read is empty.
  const std::string block(1 << 16, 'b');
  Sha256 hash;
  hash.update(bytes_of(block));
  EXPECT_EQ(sha256_of_file(write("block", block)), to_hex(hash.finish()));
  EXPECT_THROW((void)sha256_of_file(dir / "missing"), std::runtime_error);
  EXPECT_THROW((void)sha256_of_file(dir), std::runtime_error);  // a directory opens, and reads nothing
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace flexbody::format::detail
