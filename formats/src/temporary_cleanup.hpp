#pragma once
// temporary_cleanup.hpp (private): the temporary body file being written, recorded so that a signal handler
// can remove it (remove_temporary_body_file_on_signal, body_file.hpp).

#include <filesystem>

namespace flexbody::format::detail {

/// While it lives, a SIGINT, SIGTERM or SIGHUP handled by remove_temporary_body_file_on_signal removes `path`
/// (made absolute here). One at a time per process: a second one replaces the first until it ends.
class TemporaryFileGuard {
 public:
  explicit TemporaryFileGuard(const std::filesystem::path& path);
  ~TemporaryFileGuard();
  TemporaryFileGuard(const TemporaryFileGuard&) = delete;
  TemporaryFileGuard& operator=(const TemporaryFileGuard&) = delete;
};

}  // namespace flexbody::format::detail
