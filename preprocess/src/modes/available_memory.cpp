#include "available_memory.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace flexbody::preprocess::detail {
namespace {

namespace fs = std::filesystem;

// The first number in `path`; nullopt if it cannot be read or holds none ("max": no limit in cgroup v2).
std::optional<std::uint64_t> number_in(const fs::path& path) {
  std::ifstream in(path);
  std::uint64_t value = 0;
  if (in >> value) return value;
  return std::nullopt;
}

// The value of `key` in a "key value" file (/proc/meminfo, a cgroup's memory.stat); nullopt if absent.
std::optional<std::uint64_t> keyed_value(const fs::path& path, const std::string& key) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string name;
    std::uint64_t value = 0;
    if (fields >> name >> value && name == key) return value;
  }
  return std::nullopt;
}

// The room under the memory limits of this process's cgroup and of every cgroup above it (a batch system or a
// systemd slice may set the limit on a parent: a Slurm step's own memory.max is often "max"): the smallest limit
// minus its usage, the inactive page cache not counted as used (the kernel reclaims it first, as `docker stats`
// counts it). cgroup v2 ("0::/path" in /proc/self/cgroup; memory.max, memory.current, inactive_file) and v1 (the
// "memory" controller's line; memory.limit_in_bytes, memory.usage_in_bytes, total_inactive_file).
std::optional<std::uint64_t> cgroup_room(const fs::path& proc, const fs::path& cgroup) {
  struct Layout {
    fs::path root;
    std::string limit, usage, inactive;
  };
  std::ifstream in(proc / "self/cgroup");
  std::string line;
  std::vector<std::pair<Layout, fs::path>> hierarchies;
  while (std::getline(in, line)) {
    const std::size_t first = line.find(':'), second = line.find(':', first + 1);
    if (first == std::string::npos || second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1);
    const fs::path relative = fs::path(line.substr(second + 1)).relative_path();
    if (line.compare(0, 3, "0::") == 0)
      hierarchies.push_back({{cgroup, "memory.max", "memory.current", "inactive_file"}, relative});
    else if (("," + controllers + ",").find(",memory,") != std::string::npos)
      hierarchies.push_back({{cgroup / "memory", "memory.limit_in_bytes", "memory.usage_in_bytes",
                              "total_inactive_file"},
                             relative});
  }
  std::optional<std::uint64_t> room;
  for (const auto& [layout, relative] : hierarchies) {
    // From the process's own cgroup up to the root (inside a container the root is its own cgroup).
    for (fs::path dir = layout.root / relative;; dir = dir.parent_path()) {
      const std::optional<std::uint64_t> limit = number_in(dir / layout.limit);
      if (limit) {
        std::uint64_t used = number_in(dir / layout.usage).value_or(0);
        used -= std::min(used, keyed_value(dir / "memory.stat", layout.inactive).value_or(0));
        const std::uint64_t here = *limit > used ? *limit - used : 0;
        room = room ? std::min(*room, here) : here;
      }
      if (dir == layout.root || dir.string().size() <= layout.root.string().size()) break;
    }
  }
  return room;
}

}  // namespace

std::optional<std::uint64_t> available_memory_bytes() { return available_memory_bytes("/proc", "/sys/fs/cgroup"); }

std::optional<std::uint64_t> available_memory_bytes(const std::filesystem::path& proc, const std::filesystem::path& cgroup) {
  std::optional<std::uint64_t> kernel = keyed_value(proc / "meminfo", "MemAvailable:");
  if (kernel) *kernel *= 1024;  // kB
  const std::optional<std::uint64_t> room = cgroup_room(proc, cgroup);
  if (kernel && room) return std::min(*kernel, *room);
  return kernel ? kernel : room;
}

}  // namespace flexbody::preprocess::detail
