#pragma once
// body_file_seal.hpp (private): the integrity seal of a body file (SCHEMA.md, "Seal"), written and checked
// with plain file I/O so that a damaged file is refused before the HDF5 library parses any of it.
//
// The seal is the file's HDF5 user block: its first kSealBytes bytes, ASCII text padded with NUL bytes,
//
//   flexbody seal 1
//   algorithm sha256
//   hdf5_bytes <the file's length minus kSealBytes, decimal>
//   digest <SHA-256 of those bytes, 64 lowercase hex digits>
//
// and nothing else: a reader rebuilds this block from the two numbers and compares every byte.

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace flexbody::format::detail {

/// Size of the HDF5 user block that holds the seal; the HDF5 part of the file starts there.
inline constexpr std::size_t kSealBytes = 512;

/// Writes the seal into the user block of the closed HDF5 file at `path`, created with a user block of
/// kSealBytes. Throws BodyFileError naming `file_label` if the file cannot be read or written.
void write_seal(const std::filesystem::path& path, const std::string& file_label);

/// What the first bytes of a file say about its seal.
enum class SealState {
  absent,   ///< no seal: an unsealed (version 3) HDF5 file, or not an HDF5 file at all
  valid,    ///< a seal that matches the file's length and digest
  damaged,  ///< a seal (or what remains of one) that does not match: `problem` says how
};

struct SealCheck {
  SealState state = SealState::absent;
  std::string problem;  ///< for `damaged`: what does not match, e.g. "its seal is damaged"
};

/// Checks the seal of a file from its bytes (read_file_image), before the HDF5 library sees them.
[[nodiscard]] SealCheck check_seal(std::string_view bytes);

/// The one-line refusal of a file without a seal where one is required.
[[nodiscard]] std::string unsealed_message(const std::string& file_label);

/// The one-line refusal of a file whose seal does not match, with what to do about an intended edit.
[[nodiscard]] std::string damaged_message(const std::string& file_label, const std::string& problem);

}  // namespace flexbody::format::detail
