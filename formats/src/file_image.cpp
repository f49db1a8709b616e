// file_image.cpp: read_file_image() (file_image.hpp).
#include "file_image.hpp"
#include "posix_file.hpp"

#include "flexbody/format/body_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <system_error>

namespace flexbody::format::detail {
namespace {

/// What a file that is not a regular file is, for the message.
std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  return "not a regular file";
}

}  // namespace

std::vector<char> read_file_image(const std::filesystem::path& path, const std::string& file_label) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer; it is refused below by what fstat says.
  const FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (fd.get() < 0) {
    if (errno == ENOENT) throw BodyFileError(file_label + ": no such file");
    throw BodyFileError(file_label + ": cannot be opened for reading: " + last_error());
  }
  struct stat status {};
  if (::fstat(fd.get(), &status) != 0) throw BodyFileError(file_label + ": cannot be read: " + last_error());
  if (!S_ISREG(status.st_mode)) {
    throw BodyFileError(file_label + ": is " + kind_of(status.st_mode) + ", not a body file");
  }
  std::vector<char> bytes(static_cast<std::size_t>(status.st_size));
  std::size_t done = 0;
  for (;;) {
    if (done == bytes.size()) bytes.resize(bytes.size() + 4096);  // the file grew: read on to its end
    const ssize_t n = ::read(fd.get(), bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw BodyFileError(file_label + ": cannot be read: " + last_error());
    if (n == 0) break;
    done += static_cast<std::size_t>(n);
  }
  bytes.resize(done);
  return bytes;
}

}  // namespace flexbody::format::detail
