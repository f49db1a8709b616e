#pragma once
// available_memory.hpp (internal): how much memory this process can still take, so that a factorization that cannot
// fit is refused before the work (CHOLMOD's "status -2" came after up to 80 s).

#include <cstdint>
#include <filesystem>
#include <optional>

namespace flexbody::preprocess::detail {

/// The memory this process can still allocate without swapping or being killed [bytes]: the smaller of the kernel's
/// MemAvailable (/proc/meminfo) and the room left under the memory limits of its cgroup and every cgroup above it
/// (v2 or v1; a container, a batch system or a systemd slice sets them), the inactive page cache counted as free;
/// nullopt where neither can be read.
[[nodiscard]] std::optional<std::uint64_t> available_memory_bytes();
/// The same read from other roots than /proc and /sys/fs/cgroup (tests: a container's or a batch job's files).
[[nodiscard]] std::optional<std::uint64_t> available_memory_bytes(const std::filesystem::path& proc,
                                                                  const std::filesystem::path& cgroup);

}  // namespace flexbody::preprocess::detail
