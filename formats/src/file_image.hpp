#pragma once
// file_image.hpp (private): a body file read into memory once, so that the seal is checked on exactly the bytes
// HDF5 then parses (no window in which the file can change between the two), and only regular files are read:
// opening a FIFO for reading waits for a writer forever, and a device such as /dev/zero never ends.

#include <filesystem>
#include <string>
#include <vector>

namespace flexbody::format::detail {

/// Every byte of the regular file at `path`. Throws BodyFileError naming `file_label` if the path does not exist,
/// is a directory or not a regular file, cannot be opened (with the system's reason: "Permission denied"), or
/// cannot be read in full.
[[nodiscard]] std::vector<char> read_file_image(const std::filesystem::path& path, const std::string& file_label);

}  // namespace flexbody::format::detail
