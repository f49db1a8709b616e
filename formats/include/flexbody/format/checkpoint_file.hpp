#pragma once
// flexbody/format/checkpoint_file.hpp: a run's checkpoint (fbsim's DIR/checkpoint.h5): named arrays of numbers and
// texts that a simulator writes to continue a run later, bit for bit, sealed and written atomically as body files
// are (SCHEMA.md, "Checkpoint file"). What the arrays mean is the simulator's (flexbody::scene); this layer only
// stores them exactly and refuses a file that is damaged, unsealed or not a checkpoint.

#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace flexbody::format {

/// The checkpoint schema's name and version (/format, /format_version).
inline constexpr const char* kCheckpointFormatName = "flexbody checkpoint";
inline constexpr int kCheckpointFormatVersion = 1;

struct CheckpointData {
  std::string created_by;  ///< the program and its version, e.g. "fbsim 0.19.0"
  double time = 0.0;       ///< the simulated time of the state [s]
  /// Every number of the state, by name: integers (counts, byte offsets) are stored as doubles, exact below 2^53.
  /// Names are 1 to 200 characters of letters, digits, '_', '.' and '-'.
  std::map<std::string, std::vector<double>> numbers;
  std::map<std::string, std::string> texts;  ///< the same for texts (bytes; any length)
};

/// SHA-256 of `bytes`, 64 lowercase hex digits (what a checkpoint records of its scene; hashlib's hexdigest()).
[[nodiscard]] std::string sha256_hex(std::string_view bytes);

/// Writes `checkpoint` to `path` atomically: a temporary file beside it, sealed, synced and renamed onto it, so that
/// a stop at any moment leaves the previous checkpoint or the new one, never a part. Throws BodyFileError naming the
/// file, or std::invalid_argument for a name outside the rule above or a non-finite number.
void write_checkpoint_file(const CheckpointData& checkpoint, const std::filesystem::path& path);

/// Reads a checkpoint. Throws BodyFileDamaged for a seal that does not match the bytes, BodyFileError for a missing
/// or unsealed file, one that is not a checkpoint (a body file, say) or of another version, or a malformed entry,
/// each in one line naming the file.
[[nodiscard]] CheckpointData read_checkpoint_file(const std::filesystem::path& path);

}  // namespace flexbody::format
