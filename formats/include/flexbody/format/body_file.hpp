#pragma once
// flexbody/format/body_file.hpp: read and write flexible body files (*.fbh5, HDF5).
//
// \code
//   flexbody::format::BodyData body = flexbody::format::read_body_file("bracket.fbh5");
//   std::cout << body.modes.frequencies_hz.transpose() << "\n";
// \endcode

#include "flexbody/format/body_data.hpp"

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace flexbody::format {

/// Thrown for every problem with a body file; the message names the file, the dataset or attribute,
/// and what was expected against what was found. It is always one line of at most kMessageLimit bytes: text taken
/// from a file (a name, a unit, HDF5's own description) may hold control characters or be huge, so control
/// characters become spaces and a longer message is cut, saying how long it was.
class BodyFileError : public std::runtime_error {
 public:
  static constexpr std::size_t kMessageLimit = 1000;
  explicit BodyFileError(const std::string& message);
};

/// Thrown when a file's seal shows that its bytes changed after it was written: damaged in storage or
/// transfer, or edited (SCHEMA.md, "Seal"). The message is one line that says how to re-seal an intended edit.
class BodyFileDamaged : public BodyFileError {
 public:
  using BodyFileError::BodyFileError;
};

/// How read_body_file() treats the seal.
struct ReadOptions {
  /// true (the default, for simulators): a version-4 file must carry a seal that matches its bytes, checked
  /// with plain file I/O before the HDF5 library parses anything, so a damaged file never reaches it.
  /// false: a seal is checked if present (BodyData::sealed says how it went) but a missing or mismatching one
  /// is no error, and the file goes through every other check. That is for a file edited on purpose (with
  /// h5py) before `fbprep seal` re-seals it; HDF5 then parses bytes nobody vouched for.
  bool require_seal = true;
};

/// For a program that owns its process (fbprep, fbsim): tells HDF5 not to run its cleanup at exit, which after a
/// damaged file can print lines of its own after the program's error line. Call before any other HDF5 use; a
/// simulator that uses HDF5 itself should not call it (its files would not be flushed at exit).
void skip_hdf5_cleanup_at_exit();

/// For a program that owns its process (fbprep): on SIGINT, SIGTERM and SIGHUP, removes the temporary file that
/// write_body_file is writing at that moment (if any), then lets the signal end the process as it would have
/// (default action, re-raised). Signals the process ignores (nohup) stay ignored. Without it, an interrupted write
/// leaves `.NAME.tmp-PID-N` beside the target; SIGKILL always does. Call once, early, from the main thread; a
/// simulator with its own signal handling should not call it.
void remove_temporary_body_file_on_signal();

/// Whether the file at `path` begins like a body file: with a flexbody seal or HDF5's signature at byte 0 (a
/// body file, possibly damaged or unsealed, or another HDF5 file). False when it cannot be read. For programs that
/// replace an existing file with a body file only when the file was one (fbprep -o, fbprep seal -o).
[[nodiscard]] bool begins_like_body_file(const std::filesystem::path& path);

/// The SHA-256 digest (64 lowercase hex digits) that the seal of the file at `path` records for its contents, read
/// from its first 512 bytes without reading the rest; "" for a file without a seal or that cannot be read. It names a
/// body file's contents cheaply: a checkpoint records its bodies' digests, so that a resume with another file is
/// refused (read_body_file is what checks that the contents match it).
[[nodiscard]] std::string recorded_sha256(const std::filesystem::path& path);

/// Checks that `body` is complete and consistent (shapes against each other, finite numbers).
/// Throws BodyFileError naming the first problem found.
void validate(const BodyData& body);

/// Writes `body` atomically: to a temporary file beside `path`, sealed, then renamed onto it. A failure at
/// any point leaves no file under `path` (and an existing file there untouched). Validates first.
void write_body_file(const BodyData& body, const std::filesystem::path& path);

/// Reads a body file and validates it. Throws BodyFileDamaged for a file whose seal does not match (see
/// ReadOptions), BodyFileError for a missing file, a file that is not a flexbody file, another format
/// version, missing datasets, wrong shapes or non-finite values.
[[nodiscard]] BodyData read_body_file(const std::filesystem::path& path, const ReadOptions& options = {});

}  // namespace flexbody::format
