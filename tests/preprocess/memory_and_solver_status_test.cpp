// What fbprep knows about memory before a factorization (available_memory.hpp), and what it says when MUMPS runs out
// of it (mumps_status.hpp): issue 28, item 4. The cgroup reading is checked on made-up /proc and /sys/fs/cgroup trees,
// as a container (cgroup v2, the limit on a parent: a Slurm step's own memory.max is "max") and an older host
// (cgroup v1) lay them out.
#include "modes/available_memory.hpp"
#include "parallel/mumps_status.hpp"
#include "test_meshes.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace fp = flexbody::preprocess;

namespace {

constexpr std::uint64_t kGiB = 1024ULL * 1024 * 1024;

void put(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

}  // namespace

TEST(AvailableMemory, TheSmallestRoomUnderTheKernelAndEveryCgroupAbove) {
  const auto root = flexbody::test::scratch_dir();
  const auto proc = root / "proc", cgroup = root / "cgroup";
  put(proc / "meminfo", "MemTotal:       25165824 kB\nMemAvailable:   20971520 kB\n");  // 20 GiB available
  // v2: the job's own cgroup has no limit, its parent allows 8 GiB of which 3 are used, 1 of them reclaimable cache.
  put(proc / "self/cgroup", "0::/batch.slice/job42\n");
  put(cgroup / "batch.slice/memory.max", std::to_string(8 * kGiB) + "\n");
  put(cgroup / "batch.slice/memory.current", std::to_string(3 * kGiB) + "\n");
  put(cgroup / "batch.slice/memory.stat", "anon 2147483648\ninactive_file " + std::to_string(kGiB) + "\n");
  put(cgroup / "batch.slice/job42/memory.max", "max\n");
  put(cgroup / "batch.slice/job42/memory.current", std::to_string(2 * kGiB) + "\n");
  EXPECT_EQ(fp::detail::available_memory_bytes(proc, cgroup), 6 * kGiB);
  // No cgroup limit anywhere: the kernel's MemAvailable.
  put(cgroup / "batch.slice/memory.max", "max\n");
  EXPECT_EQ(fp::detail::available_memory_bytes(proc, cgroup), 20 * kGiB);
  // A limit already exceeded leaves no room (not a wrapped-around huge number).
  put(cgroup / "batch.slice/job42/memory.max", std::to_string(kGiB) + "\n");
  EXPECT_EQ(fp::detail::available_memory_bytes(proc, cgroup), 0u);

  // v1: the memory controller's own hierarchy and file names.
  const auto old_proc = root / "proc1", old_cgroup = root / "cgroup1";
  put(old_proc / "meminfo", "MemAvailable:   4194304 kB\n");  // 4 GiB
  put(old_proc / "self/cgroup", "12:cpu,cpuacct:/docker/abc\n11:memory:/docker/abc\n");
  put(old_cgroup / "memory/docker/abc/memory.limit_in_bytes", std::to_string(2 * kGiB) + "\n");
  put(old_cgroup / "memory/docker/abc/memory.usage_in_bytes", std::to_string(kGiB) + "\n");
  put(old_cgroup / "memory/docker/abc/memory.stat", "total_inactive_file " + std::to_string(kGiB / 2) + "\n");
  EXPECT_EQ(fp::detail::available_memory_bytes(old_proc, old_cgroup), 2 * kGiB - kGiB / 2);
  // Nothing readable: unknown, not zero.
  EXPECT_FALSE(fp::detail::available_memory_bytes(root / "none", root / "none").has_value());
}

// On this machine: some room, and no more than the kernel's total.
TEST(AvailableMemory, ThisMachinesIsPlausible) {
  const std::optional<std::uint64_t> room = fp::detail::available_memory_bytes();
  ASSERT_TRUE(room.has_value());
  EXPECT_GT(*room, 64ULL * 1024 * 1024);
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  std::uint64_t total_kb = 0;
  meminfo >> key >> total_kb;
  ASSERT_EQ(key, "MemTotal:");
  EXPECT_LE(*room, total_kb * 1024);
}

// PETSc's messages of MUMPS failures (its mumps.c: "MUMPS error in numerical factorization: INFOG(1)=%d, INFO(2)=%d")
// get their meaning and the ways out appended; other messages pass unchanged.
TEST(MumpsStatus, OutOfMemoryIsSaidInWords) {
  const std::string oom = "shift-invert: MUMPS error in numerical factorization: INFOG(1)=-13, INFO(2)=-2500 (PETSc error 76)";
  EXPECT_EQ(fp::detail::mumps_status(oom), -13);
  const std::string said = fp::detail::with_mumps_words(oom);
  EXPECT_EQ(said.rfind(oom, 0), 0u) << said;  // the original first
  EXPECT_NE(said.find("MUMPS ran out of memory: it could not allocate 2500 MB"), std::string::npos) << said;
  EXPECT_NE(said.find("--order 1"), std::string::npos) << said;
  EXPECT_EQ(said.find('\n'), std::string::npos);  // one line
  const std::string small = fp::detail::with_mumps_words("MUMPS error in numerical factorization: INFOG(1)=-9, INFO(2)=77");
  EXPECT_NE(small.find("-st_mat_mumps_icntl_14"), std::string::npos) << small;
  EXPECT_NE(fp::detail::with_mumps_words("MUMPS error: INFOG(1)=-19, INFO(2)=1").find("icntl_23"), std::string::npos);
  for (int code : {-8, -9, -10, -11, -12, -13, -14, -15, -17, -19, -20})
    EXPECT_FALSE(fp::detail::mumps_status_words(code, std::nullopt).empty()) << code;
  const std::string other = "KSPSolve: Zero pivot in LU factorization (PETSc error 71)";
  EXPECT_EQ(fp::detail::with_mumps_words(other), other);
  EXPECT_EQ(fp::detail::with_mumps_words("MUMPS error: INFOG(1)=-3"), "MUMPS error: INFOG(1)=-3");  // no words for it
  EXPECT_FALSE(fp::detail::mumps_status("MUMPS error without a status").has_value());
}
