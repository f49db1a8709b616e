#include "available_memory.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace flexbody::preprocess::detail {
namespace {

// The first number in `path` (memory.max holds "max" when there is no limit: nullopt then).
std::optional<std::uint64_t> number_in(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::uint64_t value = 0;
  if (in >> value) return value;
  return std::nullopt;
}

// MemAvailable from /proc/meminfo [bytes].
std::optional<std::uint64_t> kernel_available() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string key;
    std::uint64_t kilobytes = 0;
    if (fields >> key >> kilobytes && key == "MemAvailable:") return kilobytes * 1024;
  }
  return std::nullopt;
}

// The room under this process's cgroup v2 memory limit [bytes]: its directory is the "0::" line of /proc/self/cgroup
// under /sys/fs/cgroup (or /sys/fs/cgroup itself inside a container that shows its own cgroup as the root).
std::optional<std::uint64_t> cgroup_room() {
  std::ifstream in("/proc/self/cgroup");
  std::string line, relative;
  while (std::getline(in, line))
    if (line.rfind("0::", 0) == 0) relative = line.substr(3);
  const std::filesystem::path root = "/sys/fs/cgroup";
  for (const std::filesystem::path& dir : {root / std::filesystem::path(relative).relative_path(), root}) {
    const std::optional<std::uint64_t> limit = number_in(dir / "memory.max");
    if (!limit) continue;
    const std::uint64_t used = number_in(dir / "memory.current").value_or(0);
    return *limit > used ? *limit - used : 0;
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::uint64_t> available_memory_bytes() {
  const std::optional<std::uint64_t> kernel = kernel_available(), room = cgroup_room();
  if (kernel && room) return std::min(*kernel, *room);
  return kernel ? kernel : room;
}

}  // namespace flexbody::preprocess::detail
