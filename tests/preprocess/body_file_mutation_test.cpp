// body_file_mutation_test.cpp: a bounded, deterministic byte-level fuzz run of the sealed body file. 300 copies
// of a small body file written by fbprep, each changed once (a flipped bit, a zeroed 64-byte block or a
// truncation; seeded), go through `fbprep inspect --json`. The seal is checked before HDF5 parses anything, so
// every one must be refused the same way: exit code 2, one line on stderr, nothing on stdout, no signal and no
// hang (10 s each, against about 0.3 s for a run). Half of the changes are aimed at the first 4 KiB, where the
// seal, the superblock and most of HDF5's metadata sit.
#include "bounded_run.hpp"
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

namespace {

constexpr int kCases = 300;
constexpr std::uint64_t kSeed = 20261123;
constexpr std::size_t kMetadataBytes = 4096;
constexpr std::size_t kBlockBytes = 64;
constexpr std::chrono::seconds kLimit{10};

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream bytes;
  bytes << file.rdbuf();
  return bytes.str();
}

struct Mutation {
  std::string description;
  std::string bytes;
};

/// Case `index` of the run: a changed copy of `good` (never equal to it), from a generator seeded per case so
/// that any single case can be reproduced alone.
Mutation mutate(const std::string& good, int index) {
  std::mt19937_64 random(kSeed + static_cast<std::uint64_t>(index));
  const bool aimed = index % 2 == 0;  // at the first 4 KiB
  auto position = [&](std::size_t size) {
    const std::size_t range = aimed ? std::min(size, kMetadataBytes) : size;
    return std::uniform_int_distribution<std::size_t>(0, range - 1)(random);
  };
  Mutation m{"", good};
  switch (index % 3) {
    case 0: {
      const std::size_t at = position(good.size());
      const int bit = std::uniform_int_distribution<int>(0, 7)(random);
      m.bytes[at] = static_cast<char>(m.bytes[at] ^ (1 << bit));
      m.description = fmt::format("bit {} of byte {} flipped", bit, at);
      break;
    }
    case 1: {
      std::size_t at = 0;
      do {  // a block that is already zero would change nothing: draw again
        at = position(good.size() - kBlockBytes + 1);
      } while (std::all_of(good.begin() + static_cast<std::ptrdiff_t>(at),
                           good.begin() + static_cast<std::ptrdiff_t>(at + kBlockBytes), [](char c) { return c == 0; }));
      std::fill_n(m.bytes.begin() + static_cast<std::ptrdiff_t>(at), kBlockBytes, '\0');
      m.description = fmt::format("bytes {} to {} zeroed", at, at + kBlockBytes - 1);
      break;
    }
    default: {
      const std::size_t length = 1 + position(good.size() - 1);  // 1 ... size - 1 bytes kept
      m.bytes.resize(length);
      m.description = fmt::format("truncated to {} bytes", length);
      break;
    }
  }
  return m;
}

}  // namespace

TEST(BodyFileMutation, EveryChangedCopyIsRefusedWithOneLineAndExitCode2) {
  const auto dir = flexbody::test::scratch_dir();
  flexbody::test::write_text(dir / "box.geo", "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 0.1, 0.02, 0.02};\n");
  const flexbody::test::CliRun prep =
      flexbody::test::run_fbprep(dir, "box.geo --unit m --mesh-size 0.02 --modes 2 -o good.fbh5 --quiet");
  ASSERT_EQ(prep.exit_code, 0) << prep.err;
  const std::string good = read_bytes(dir / "good.fbh5");
  ASSERT_GT(good.size(), 2 * kMetadataBytes);

  // The cases run on every core (each run is mostly the dynamic loader starting fbprep).
  std::atomic<int> next{0};
  std::mutex report;
  auto worker = [&] {
    for (int index = next++; index < kCases; index = next++) {
      const Mutation m = mutate(good, index);
      const std::filesystem::path stem = dir / fmt::format("case{:03}", index);
      const std::filesystem::path file = stem.string() + ".fbh5";
      std::ofstream(file, std::ios::binary) << m.bytes;
      const flexbody::test::BoundedRun run =
          flexbody::test::run_bounded(FLEXBODY_FBPREP, {"inspect", "--json", file.string()}, stem, kLimit);
      const bool ok = run.exit_code == 2 && run.signal == 0 && !run.timed_out && run.out.empty() &&
                      std::count(run.err.begin(), run.err.end(), '\n') == 1 &&
                      run.err.rfind("fbprep: error: " + file.string() + ": damaged or modified after it was written: ",
                                    0) == 0;
      const std::lock_guard lock(report);
      EXPECT_TRUE(ok) << "case " << index << " (" << m.description << "): exit code " << run.exit_code
                      << ", signal " << run.signal << (run.timed_out ? ", timed out" : "") << ", "
                      << run.elapsed.count() << " s, stdout \"" << run.out << "\", stderr \"" << run.err << "\"";
      if (ok)  // a failed case keeps its file and output for a look
        for (const char* extension : {".fbh5", ".out", ".err"}) std::filesystem::remove(stem.string() + extension);
    }
  };
  std::vector<std::thread> workers(std::max(2u, std::thread::hardware_concurrency()));
  for (std::thread& t : workers) t = std::thread(worker);
  for (std::thread& t : workers) t.join();
}
