// checkpoint_file_test.cpp: a checkpoint's numbers and texts come back exactly; damaged, unsealed, foreign and
// malformed files are refused in one line naming the file; a write replaces the old checkpoint atomically.
#include "test_body.hpp"

#include "flexbody/format/body_file.hpp"
#include "flexbody/format/checkpoint_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace flexbody::format::test {
namespace {

class CheckpointFile : public TempDirTest {
 protected:
  static CheckpointData sample() {
    CheckpointData c;
    c.created_by = "fbsim test";
    c.time = 0.1 + 0.2;  // not a short decimal: the bits must survive
    c.numbers["integrator.q"] = {1.0, -0.0, std::nextafter(1.0, 2.0), 1e-300, -3.5e300};
    c.numbers["run.count"] = {9007199254740991.0};  // 2^53 - 1: the largest exact integer
    c.numbers["empty"] = {};
    c.texts["warnings"] = std::string("line one\nline two with \0 inside", 30) + std::string(70000, 'x');
    c.texts["none"] = "";
    return c;
  }
  static std::string refusal(const std::filesystem::path& path) {
    try {
      (void)read_checkpoint_file(path);
    } catch (const BodyFileError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(CheckpointFile, RoundTripIsExact) {
  const auto path = dir() / "checkpoint.h5";
  const CheckpointData written = sample();
  write_checkpoint_file(written, path);
  EXPECT_EQ(recorded_sha256(path).size(), 64u);
  const CheckpointData read = read_checkpoint_file(path);
  EXPECT_EQ(read.created_by, "fbsim test");
  EXPECT_EQ(read.time, written.time);
  ASSERT_EQ(read.numbers.size(), written.numbers.size());
  for (const auto& [name, values] : written.numbers) {
    ASSERT_EQ(read.numbers.at(name).size(), values.size()) << name;
    for (std::size_t k = 0; k < values.size(); ++k) {
      EXPECT_EQ(read.numbers.at(name)[k], values[k]) << name << "[" << k << "]";
      EXPECT_EQ(std::signbit(read.numbers.at(name)[k]), std::signbit(values[k])) << name << "[" << k << "]";
    }
  }
  EXPECT_EQ(read.texts, written.texts);
}

TEST_F(CheckpointFile, ReplacingKeepsOneWholeFile) {
  const auto path = dir() / "checkpoint.h5";
  CheckpointData c = sample();
  write_checkpoint_file(c, path);
  c.time = 2.0;
  write_checkpoint_file(c, path);
  EXPECT_EQ(read_checkpoint_file(path).time, 2.0);
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir())) ++files;
  EXPECT_EQ(files, 1);  // no temporary left beside it
}

TEST_F(CheckpointFile, BadEntriesAreRefusedBeforeAnyFile) {
  const auto path = dir() / "checkpoint.h5";
  CheckpointData c = sample();
  c.numbers["a/b"] = {1.0};
  EXPECT_THROW(write_checkpoint_file(c, path), std::invalid_argument);
  c = sample();
  c.numbers["nan"] = {std::numeric_limits<double>::quiet_NaN()};
  EXPECT_THROW(write_checkpoint_file(c, path), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST_F(CheckpointFile, DamagedUnsealedAndForeignFilesAreRefused) {
  const auto path = dir() / "checkpoint.h5";
  write_checkpoint_file(sample(), path);
  const std::string good = read_bytes(path);
  // One byte changed anywhere after the seal: the digest differs.
  std::string damaged = good;
  damaged[good.size() / 2] = static_cast<char>(damaged[good.size() / 2] ^ 0x01);
  std::filesystem::remove(path);
  write_bytes(path, damaged);
  EXPECT_THROW((void)read_checkpoint_file(path), BodyFileDamaged);
  EXPECT_NE(refusal(path).find("damaged or modified"), std::string::npos) << refusal(path);
  // Truncated.
  std::filesystem::remove(path);
  write_bytes(path, good.substr(0, good.size() - 100));
  EXPECT_NE(refusal(path).find("truncated"), std::string::npos) << refusal(path);
  // The HDF5 part without its seal.
  std::filesystem::remove(path);
  write_bytes(path, good.substr(512));
  EXPECT_NE(refusal(path).find("no flexbody seal"), std::string::npos) << refusal(path);
  // Text, and nothing.
  std::filesystem::remove(path);
  write_bytes(path, "t [s],x\n0,1\n");
  EXPECT_NE(refusal(path).find("not a checkpoint"), std::string::npos) << refusal(path);
  EXPECT_NE(refusal(dir() / "missing.h5").find("missing.h5"), std::string::npos);
  // A body file is not a checkpoint.
  const auto body = dir() / "body.fbh5";
  write_body_file(make_body(), body);
  EXPECT_NE(refusal(body).find("is a body file, not a checkpoint"), std::string::npos) << refusal(body);
  for (const auto& p : {path, body}) EXPECT_EQ(refusal(p).find('\n'), std::string::npos);
}

}  // namespace
}  // namespace flexbody::format::test
