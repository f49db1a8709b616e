#pragma once
// sealed_write.hpp (private): how every flexbody HDF5 file is written (body files, checkpoints): into a temporary
// file beside the target, which a SIGINT/SIGTERM/SIGHUP handler removes (temporary_cleanup.hpp), sealed, synced to
// disk and renamed onto the target. A failure at any point leaves no file under the target's name and an existing
// file there untouched.

#include "hdf5_io.hpp"

#include <filesystem>
#include <functional>
#include <string>

namespace flexbody::format::detail {

/// Writes the file at `path` atomically: `layout` writes the HDF5 objects into the Location it is given (a new file
/// with the seal's user block), then the file is closed, sealed (body_file_seal.hpp) and moved onto `path`. Throws
/// BodyFileError naming `label`.
void write_sealed_file(const std::filesystem::path& path, const std::string& label,
                       const std::function<void(const Location& file)>& layout);

}  // namespace flexbody::format::detail
