#pragma once
// posix_file.hpp (private): what the body file's reader, its seal and sha256_of_file share about POSIX files: a
// descriptor closed on scope exit, errno's message for an error line, reads that survive signals, and the SHA-256 of
// a file's bytes (file_digest.cpp).

#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <system_error>
#include <utility>

namespace flexbody::format::detail {

/// A POSIX file descriptor closed on scope exit (a negative one, a failed open, is not closed).
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) noexcept : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  [[nodiscard]] int get() const noexcept { return fd_; }

 private:
  int fd_;
};

/// The system's reason for the last failed call ("Permission denied").
inline std::string last_error() { return std::generic_category().message(errno); }

/// Reads up to `size` bytes at `offset`, retrying interrupted and short reads; fewer only at the end.
/// Returns -1 on a read error (errno set).
long long read_at(int fd, char* data, std::size_t size, std::uint64_t offset);

/// SHA-256 of the bytes from `offset` to the end (lowercase hex), and their count; nullopt on a read error (errno set).
std::optional<std::pair<std::string, std::uint64_t>> digest_from(int fd, std::uint64_t offset);

}  // namespace flexbody::format::detail
