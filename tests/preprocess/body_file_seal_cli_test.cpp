// body_file_seal_cli_test.cpp: sealed body files as a user meets them: `fbprep inspect` refuses one whose bytes
// changed after fbprep wrote it (one line, exit code 2), an h5py edit needs `fbprep seal`, version-3 files still
// read and convert, and Python checks the seal with hashlib alone, as SCHEMA.md shows.
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace {

using flexbody::test::CliRun;

constexpr std::size_t kSeal = 512;

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream bytes;
  bytes << file.rdbuf();
  return bytes.str();
}

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

/// A small body file (a steel box of 110 nodes, 2 modes, 0.1 x 0.02 x 0.02 m) written by fbprep into `dir`.
std::filesystem::path small_body(const std::filesystem::path& dir, const std::string& name) {
  flexbody::test::write_text(dir / "box.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 0.1, 0.02, 0.02};\n");
  const CliRun prep =
      flexbody::test::run_fbprep(dir, fmt::format("box.geo --unit m --mesh-size 0.02 --modes 2 -o {} --quiet", name));
  EXPECT_EQ(prep.exit_code, 0) << prep.err;
  return dir / name;
}

/// Expects `fbprep inspect --json` to refuse `name` in `dir` as damaged: exit code 2, nothing on stdout, one line
/// on stderr that names the file, says what happened and how to re-seal an intended edit, and holds `problem`.
void expect_refused_as_damaged(const std::filesystem::path& dir, const std::string& name, const std::string& problem) {
  SCOPED_TRACE(name);
  const CliRun run = flexbody::test::run_fbprep(dir, "inspect --json " + name);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  EXPECT_EQ(run.err.rfind("fbprep: error: " + name + ": damaged or modified after it was written: ", 0), 0u) << run.err;
  EXPECT_NE(run.err.find(problem), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("re-seal it with: fbprep seal " + name + "\n"), std::string::npos) << run.err;
}

/// Runs a Python program with the Debian python3 (h5py, numpy) in `dir`; skips the test if h5py is missing.
CliRun python(const std::filesystem::path& dir, const std::string& program) {
  flexbody::test::write_text(dir / "program.py", program);
  const std::string command =
      fmt::format("cd '{}' && /usr/bin/python3 program.py > stdout.txt 2> stderr.txt", dir.string());
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, flexbody::test::slurp(dir / "stdout.txt"),
          flexbody::test::slurp(dir / "stderr.txt")};
}

bool have_h5py() { return std::system("/usr/bin/python3 -c 'import h5py' > /dev/null 2>&1") == 0; }

/// SCHEMA.md's hashlib snippet (section "Seal", the first Python block: check_seal and reseal), so that the
/// test runs what the documentation shows.
std::string schema_seal_snippet() {
  const std::string schema = flexbody::test::slurp(std::filesystem::path(FLEXBODY_SOURCE_DIR) / "formats" / "SCHEMA.md");
  const std::size_t section = schema.find("\n## Seal\n");
  const std::size_t begin = schema.find("```python\n", section);
  const std::size_t end = schema.find("```\n", begin + 10);
  EXPECT_NE(section, std::string::npos);
  EXPECT_NE(end, std::string::npos);
  if (section == std::string::npos || end == std::string::npos) return "";
  return schema.substr(begin + 10, end - begin - 10);
}

}  // namespace

TEST(SealedBodyFile, InspectRefusesEveryChangedByteWithOneLine) {
  const auto dir = flexbody::test::scratch_dir();
  const std::string good = read_bytes(small_body(dir, "good.fbh5"));
  const CliRun fine = flexbody::test::run_fbprep(dir, "inspect --json good.fbh5");
  ASSERT_EQ(fine.exit_code, 0) << fine.err;
  EXPECT_EQ(nlohmann::json::parse(fine.out)["sealed"], true);
  EXPECT_EQ(nlohmann::json::parse(fine.out)["format_version"], 4);

  std::string flipped = good;  // one bit in the middle of the HDF5 part
  flipped[good.size() / 2] = static_cast<char>(flipped[good.size() / 2] ^ 0x04);
  write_bytes(dir / "flipped.fbh5", flipped);
  expect_refused_as_damaged(dir, "flipped.fbh5", "the SHA-256 digest of its contents differs from the one its seal records");

  std::string seal = good;  // one bit of the seal's padding
  seal[400] = static_cast<char>(seal[400] ^ 0x01);
  write_bytes(dir / "seal.fbh5", seal);
  expect_refused_as_damaged(dir, "seal.fbh5", "its seal (the first 512 bytes) is damaged");

  write_bytes(dir / "truncated.fbh5", good.substr(0, good.size() - 100));
  expect_refused_as_damaged(dir, "truncated.fbh5", "(truncated)");

  write_bytes(dir / "appended.fbh5", good + "x");
  expect_refused_as_damaged(dir, "appended.fbh5", "(bytes appended)");
}

TEST(SealedBodyFile, H5pyEditIsRefusedUntilFbprepSealsIt) {
  if (!have_h5py()) GTEST_SKIP() << "/usr/bin/python3 with h5py is not installed (scripts/setup.sh installs it)";
  const auto dir = flexbody::test::scratch_dir();
  small_body(dir, "b.fbh5");
  EXPECT_EQ(read_bytes(dir / "b.fbh5").find("GCOL"), std::string::npos);  // no global heap

  // h5py reads fbprep's fixed-length strings (as bytes) and the seal checks out with hashlib alone; then the
  // user edits an attribute, which h5py writes as a variable-length string.
  const CliRun edit = python(dir, schema_seal_snippet() + R"(
import h5py
check_seal("b.fbh5")
with h5py.File("b.fbh5", "r") as f:
    assert f.attrs["format"] == b"flexbody", f.attrs["format"]
    assert f.attrs["format_version"] == 4
    assert f["provenance/options"].attrs["order"].decode().startswith("input,output,unit")
with h5py.File("b.fbh5", "r+") as f:
    f.attrs["source_file"] = "renamed.geo"
try:
    check_seal("b.fbh5")
except AssertionError as e:
    print("after the edit:", e)
)");
  ASSERT_EQ(edit.exit_code, 0) << edit.err;
  // HDF5 may have grown the file for the new string: the length or the digest differs.
  EXPECT_EQ(edit.out.rfind("after the edit: ", 0), 0u) << edit.out;
  expect_refused_as_damaged(dir, "b.fbh5", "");

  // Re-sealed by hand with SCHEMA.md's reseal(), a copy of the edited file is still refused: h5py's str is a
  // variable-length string, which a sealed file never holds (its global heap is what crashed libhdf5) ...
  std::filesystem::copy_file(dir / "b.fbh5", dir / "by_hand.fbh5");
  const CliRun by_hand = python(dir, schema_seal_snippet() + "reseal('by_hand.fbh5')\n");
  ASSERT_EQ(by_hand.exit_code, 0) << by_hand.err;
  const CliRun refused = flexbody::test::run_fbprep(dir, "inspect --json by_hand.fbh5");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_EQ(refused.err.rfind("fbprep: error: by_hand.fbh5: its HDF5 structure is not what fbprep writes (/source_file "
                              "is a variable-length string",
                              0),
            0u)
      << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  // ... while an edit that writes numpy bytes (a fixed-length string), sealed by hand, reads again.
  small_body(dir, "fixed.fbh5");
  const CliRun fixed = python(dir, schema_seal_snippet() + R"(
import h5py, numpy as np
with h5py.File("fixed.fbh5", "r+") as f:
    f.attrs["source_file"] = np.bytes_("renamed.geo")
reseal("fixed.fbh5")
)");
  ASSERT_EQ(fixed.exit_code, 0) << fixed.err;
  const CliRun fixed_inspect = flexbody::test::run_fbprep(dir, "inspect --json fixed.fbh5");
  ASSERT_EQ(fixed_inspect.exit_code, 0) << fixed_inspect.err;
  EXPECT_EQ(nlohmann::json::parse(fixed_inspect.out)["source_file"], "renamed.geo");

  const CliRun seal = flexbody::test::run_fbprep(dir, "seal b.fbh5");
  ASSERT_EQ(seal.exit_code, 0) << seal.err;
  EXPECT_EQ(seal.err, "");
  EXPECT_EQ(seal.out, "b.fbh5 (format version 4, without a matching seal): every check passed; written sealed, "
                      "format version 4, to b.fbh5\n");
  const CliRun inspect = flexbody::test::run_fbprep(dir, "inspect --json b.fbh5");
  ASSERT_EQ(inspect.exit_code, 0) << inspect.err;
  EXPECT_EQ(nlohmann::json::parse(inspect.out)["source_file"], "renamed.geo");
  EXPECT_EQ(nlohmann::json::parse(inspect.out)["sealed"], true);
  EXPECT_EQ(read_bytes(dir / "b.fbh5").find("GCOL"), std::string::npos);  // h5py's variable-length string is gone
  const CliRun check = python(dir, schema_seal_snippet() + "check_seal('b.fbh5')\nprint('seal ok')\n");
  EXPECT_EQ(check.out, "seal ok\n") << check.err;
}

TEST(SealedBodyFile, SealRunsEveryCheckAndWritesNothingWhenOneFails) {
  if (!have_h5py()) GTEST_SKIP() << "/usr/bin/python3 with h5py is not installed (scripts/setup.sh installs it)";
  const auto dir = flexbody::test::scratch_dir();
  small_body(dir, "b.fbh5");
  const CliRun edit = python(dir, R"(
import h5py, numpy as np
with h5py.File("b.fbh5", "r+") as f:
    f["reduction/frequencies_hz"][0] = np.nan
)");
  ASSERT_EQ(edit.exit_code, 0) << edit.err;
  const std::string edited = read_bytes(dir / "b.fbh5");
  const CliRun seal = flexbody::test::run_fbprep(dir, "seal b.fbh5 -o resealed.fbh5");
  EXPECT_EQ(seal.exit_code, 1);
  EXPECT_EQ(seal.out, "");
  EXPECT_EQ(std::count(seal.err.begin(), seal.err.end(), '\n'), 1) << seal.err;
  EXPECT_NE(seal.err.find("b.fbh5: /reduction/frequencies_hz"), std::string::npos) << seal.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "resealed.fbh5"));
  EXPECT_EQ(read_bytes(dir / "b.fbh5"), edited);
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();

  const CliRun usage = flexbody::test::run_fbprep(dir, "seal");
  EXPECT_EQ(usage.exit_code, 2);
  EXPECT_EQ(std::count(usage.err.begin(), usage.err.end(), '\n'), 1) << usage.err;
  const CliRun missing = flexbody::test::run_fbprep(dir, "seal absent.fbh5");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_EQ(missing.err, "fbprep: error: absent.fbh5: no such file\n");
}

TEST(SealedBodyFile, Version3FileIsRefusedUntilSealConvertsIt) {
  // Written by fbprep before body files were sealed (tests/data/v3-body/README.md).
  const auto dir = flexbody::test::scratch_dir();
  std::filesystem::copy_file(flexbody::test::data_dir() / "v3-body" / "beam_v3.fbh5", dir / "v3.fbh5");
  const std::string original = read_bytes(dir / "v3.fbh5");

  // Refused before libhdf5 parses it (its global heap is what crashed libhdf5), with the way out.
  const CliRun inspect = flexbody::test::run_fbprep(dir, "inspect --json v3.fbh5");
  EXPECT_EQ(inspect.exit_code, 1);
  EXPECT_EQ(inspect.out, "");
  EXPECT_EQ(inspect.err.rfind("fbprep: error: v3.fbh5: is not sealed (format version 3", 0), 0u) << inspect.err;
  EXPECT_NE(inspect.err.find("convert it once with: fbprep seal v3.fbh5\n"), std::string::npos) << inspect.err;
  EXPECT_EQ(std::count(inspect.err.begin(), inspect.err.end(), '\n'), 1) << inspect.err;

  const CliRun seal = flexbody::test::run_fbprep(dir, "seal v3.fbh5 -o v4.fbh5");
  ASSERT_EQ(seal.exit_code, 0) << seal.err;
  EXPECT_EQ(seal.out, "v3.fbh5 (format version 3, unsealed): every check passed; written sealed, format version 4, "
                      "to v4.fbh5\n");
  EXPECT_EQ(read_bytes(dir / "v3.fbh5"), original);  // -o: the input stays as it was
  const CliRun converted = flexbody::test::run_fbprep(dir, "inspect --json v4.fbh5");
  ASSERT_EQ(converted.exit_code, 0) << converted.err;
  const auto v4 = nlohmann::json::parse(converted.out);
  EXPECT_EQ(v4["format_version"], 4);
  EXPECT_EQ(v4["sealed"], true);
  EXPECT_NEAR(v4["frequencies_hz"][0].get<double>(), 13056.64, 0.01);  // the README's figure for that beam
  EXPECT_EQ(read_bytes(dir / "v4.fbh5").find("GCOL"), std::string::npos);
}
