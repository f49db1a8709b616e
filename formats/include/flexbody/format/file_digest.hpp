#pragma once
// flexbody/format/file_digest.hpp: the SHA-256 of a file, as the body file's seal computes it (one implementation,
// formats/src/sha256.cpp): fbprep records its input's digest in the body file's provenance.

#include <filesystem>
#include <string>

namespace flexbody::format {

/// The SHA-256 of the file's bytes, lowercase hex (what `sha256sum` and Python's hashlib print). Throws
/// std::runtime_error naming the path if it cannot be opened or read to its end (a directory, a read error).
[[nodiscard]] std::string sha256_of_file(const std::filesystem::path& path);

}  // namespace flexbody::format
