// sealed_write.cpp: write_sealed_file (sealed_write.hpp).
#include "sealed_write.hpp"

#include "body_file_seal.hpp"
#include "temporary_cleanup.hpp"

#include "flexbody/format/body_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <system_error>

namespace flexbody::format::detail {
namespace {

/// Forces the written bytes to disk so that the rename never exposes a file with missing data.
void sync_to_disk(const std::filesystem::path& path, const std::string& label) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  const bool ok = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  if (!ok) throw BodyFileError(label + ": cannot sync the temporary file " + path.string() + " to disk");
}

std::filesystem::path temporary_beside(const std::filesystem::path& target) {
  static std::atomic<unsigned long> counter{0};
  for (;;) {
    std::string name(1, '.');  // built by appending: GCC 12 warns falsely on "literal" + std::string&&
    name += target.filename().string();
    name += ".tmp-";
    name += std::to_string(::getpid());
    name += '-';
    name += std::to_string(counter.fetch_add(1));
    std::filesystem::path candidate = target.parent_path() / name;
    std::error_code error;
    if (!std::filesystem::exists(std::filesystem::symlink_status(candidate, error))) return candidate;
  }
}

}  // namespace

void write_sealed_file(const std::filesystem::path& path, const std::string& label,
                       const std::function<void(const Location& file)>& layout) {
  if (path.filename().empty()) throw BodyFileError(label + ": not a file name");
  const QuietHdf5Errors quiet;
  const std::filesystem::path temporary = temporary_beside(path);
  const TemporaryFileGuard removed_on_signal(temporary);  // remove_temporary_body_file_on_signal
  try {
    {
      Location file = create_file(temporary, label, kSealBytes);
      layout(file);
      flush_and_close(file);
    }
    write_seal(temporary, label);  // after HDF5 closed the file: every byte of it is final
    sync_to_disk(temporary, label);
    std::error_code error;
    std::filesystem::rename(temporary, path, error);
    if (error) {
      throw BodyFileError(label + ": cannot move the temporary file " + temporary.filename().string() +
                          " onto it: " + error.message());
    }
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
}

}  // namespace flexbody::format::detail
