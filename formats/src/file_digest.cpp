// file_digest.cpp: the SHA-256 of a file's bytes, for fbprep's input (sha256_of_file, flexbody/format/file_digest.hpp)
// and the body file's seal (digest_from, posix_file.hpp).
#include "flexbody/format/file_digest.hpp"
#include "posix_file.hpp"

#include "sha256.hpp"

#include <fcntl.h>

#include <stdexcept>
#include <vector>

namespace flexbody::format {
namespace detail {

long long read_at(int fd, char* data, std::size_t size, std::uint64_t offset) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(fd, data + done, size - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return -1;
    if (n == 0) break;
    done += static_cast<std::size_t>(n);
  }
  return static_cast<long long>(done);
}

std::optional<std::pair<std::string, std::uint64_t>> digest_from(int fd, std::uint64_t offset) {
  constexpr std::size_t kChunkBytes = std::size_t{1} << 20;
  Sha256 hash;
  std::vector<char> chunk(kChunkBytes);
  std::uint64_t total = 0;
  for (;;) {
    const long long n = read_at(fd, chunk.data(), chunk.size(), offset + total);
    if (n < 0) return std::nullopt;
    hash.update({reinterpret_cast<const std::uint8_t*>(chunk.data()), static_cast<std::size_t>(n)});
    total += static_cast<std::uint64_t>(n);
    if (static_cast<std::size_t>(n) < chunk.size()) break;
  }
  return std::pair{to_hex(hash.finish()), total};
}

}  // namespace detail

std::string sha256_of_file(const std::filesystem::path& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
    throw std::runtime_error(path.string() + ": is a directory, not a file to take the SHA-256 of");
  const detail::FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) throw std::runtime_error(path.string() + ": cannot be opened for reading: " + detail::last_error());
  const auto digest = detail::digest_from(fd.get(), 0);
  if (!digest) throw std::runtime_error(path.string() + ": could not be read to its end: " + detail::last_error());
  return digest->first;
}

}  // namespace flexbody::format
