#pragma once
// posix_file.hpp (private): what the body file's reader and seal share about POSIX files: a descriptor closed on
// scope exit, and errno's message for an error line.

#include <unistd.h>

#include <cerrno>
#include <string>
#include <system_error>

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

}  // namespace flexbody::format::detail
