// body_file_seal.cpp: the integrity seal in the user block of a body file (body_file_seal.hpp, SCHEMA.md "Seal").
#include "body_file_seal.hpp"
#include "posix_file.hpp"

#include "sha256.hpp"

#include "flexbody/format/body_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <optional>
#include <string_view>
#include <system_error>
#include <vector>

namespace flexbody::format::detail {
namespace {

constexpr std::string_view kMagicLine = "flexbody seal 1\n";
constexpr std::string_view kAlgorithmLine = "algorithm sha256\n";
constexpr std::string_view kLengthKey = "hdf5_bytes ";
constexpr std::string_view kDigestKey = "digest ";
constexpr std::size_t kDigestHexDigits = 64;
constexpr std::string_view kHdf5Signature{"\x89HDF\r\n\x1a\n", 8};

using Block = std::array<char, kSealBytes>;

/// The seal for `hdf5_bytes` bytes of HDF5 data with digest `hex`: the text, then NUL bytes.
Block seal_block(std::uint64_t hdf5_bytes, const std::string& hex) {
  std::string text(kMagicLine);
  text += kAlgorithmLine;
  text += kLengthKey;
  text += std::to_string(hdf5_bytes);
  text += '\n';
  text += kDigestKey;
  text += hex;
  text += '\n';
  Block block{};  // the text is at most 16 + 17 + 31 + 72 bytes
  std::copy(text.begin(), text.end(), block.begin());
  return block;
}

/// The length and digest a seal records, if `block` is exactly a seal (seal_block of them).
struct Recorded {
  std::uint64_t hdf5_bytes = 0;
  std::string hex;
};

std::optional<Recorded> parse_block(const Block& block) {
  const std::string_view text(block.data(), block.size());
  std::size_t at = 0;
  auto expect = [&](std::string_view literal) {
    if (text.substr(at, literal.size()) != literal) return false;
    at += literal.size();
    return true;
  };
  if (!expect(kMagicLine) || !expect(kAlgorithmLine) || !expect(kLengthKey)) return std::nullopt;
  Recorded recorded;
  const std::size_t digits_begin = at;
  constexpr std::size_t kMaxDigits = 18;  // below 2^63: no overflow, and far beyond any real file
  for (; at < text.size() && text[at] >= '0' && text[at] <= '9' && at - digits_begin < kMaxDigits; ++at)
    recorded.hdf5_bytes = 10 * recorded.hdf5_bytes + static_cast<std::uint64_t>(text[at] - '0');
  if (at == digits_begin || !expect("\n") || !expect(kDigestKey)) return std::nullopt;
  recorded.hex = std::string(text.substr(at, kDigestHexDigits));
  const auto lower_hex = [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); };
  if (!std::all_of(recorded.hex.begin(), recorded.hex.end(), lower_hex)) return std::nullopt;
  // Rebuilding the block catches everything else: leading zeros, a missing newline, stray bytes anywhere
  // in the padding.
  if (seal_block(recorded.hdf5_bytes, recorded.hex) != block) return std::nullopt;
  return recorded;
}

std::uint64_t file_size(int fd) {
  struct stat status {};
  return ::fstat(fd, &status) == 0 ? static_cast<std::uint64_t>(status.st_size) : 0;
}

}  // namespace

void write_seal(const std::filesystem::path& path, const std::string& file_label) {
  const std::string what = "the temporary file " + path.filename().string();
  const FileDescriptor fd(::open(path.c_str(), O_RDWR | O_CLOEXEC));
  if (fd.get() < 0) throw BodyFileError(file_label + ": cannot open " + what + " to seal it: " + last_error());
  const std::uint64_t size = file_size(fd.get());
  if (size < kSealBytes) throw BodyFileError(file_label + ": " + what + " is shorter than its seal");
  const auto digest = digest_from(fd.get(), kSealBytes);
  if (!digest) throw BodyFileError(file_label + ": cannot read " + what + " to seal it: " + last_error());
  if (digest->second != size - kSealBytes)
    throw BodyFileError(file_label + ": " + what + " changed while it was being sealed");
  const Block block = seal_block(digest->second, digest->first);
  std::size_t done = 0;
  while (done < block.size()) {
    const ssize_t n = ::pwrite(fd.get(), block.data() + done, block.size() - done, static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw BodyFileError(file_label + ": cannot write the seal into " + what + ": " + last_error());
    done += static_cast<std::size_t>(n);
  }
}

SealCheck check_seal(std::string_view bytes) {
  const std::string_view start = bytes.substr(0, kSealBytes);
  if (start.starts_with(kHdf5Signature)) return {};  // HDF5 from byte 0: no user block, no seal
  if (start.empty() || !kMagicLine.starts_with(start.substr(0, kMagicLine.size()))) {
    // Not a seal's first line; if the HDF5 superblock follows a user block, the seal itself is damaged.
    if (bytes.size() > kSealBytes && bytes.substr(kSealBytes).starts_with(kHdf5Signature))
      return {SealState::damaged, "its seal (the first 512 bytes) is damaged"};
    return {};
  }
  if (start.size() < kSealBytes) {
    return {SealState::damaged,
            "it is truncated to " + std::to_string(start.size()) + (start.size() == 1 ? " byte" : " bytes") +
                ", less than its 512-byte seal"};
  }
  Block block{};
  std::copy(start.begin(), start.end(), block.begin());
  const std::optional<Recorded> recorded = parse_block(block);
  if (!recorded) return {SealState::damaged, "its seal (the first 512 bytes) is damaged"};
  const std::uint64_t hdf5_bytes = bytes.size() - kSealBytes;
  if (hdf5_bytes != recorded->hdf5_bytes) {
    return {SealState::damaged, "its seal records " + std::to_string(recorded->hdf5_bytes) +
                                    " bytes after the seal, the file has " + std::to_string(hdf5_bytes) +
                                    (hdf5_bytes < recorded->hdf5_bytes ? " (truncated)" : " (bytes appended)")};
  }
  Sha256 hash;
  const std::string_view hdf5 = bytes.substr(kSealBytes);
  hash.update({reinterpret_cast<const std::uint8_t*>(hdf5.data()), hdf5.size()});
  if (to_hex(hash.finish()) != recorded->hex)
    return {SealState::damaged, "the SHA-256 digest of its contents differs from the one its seal records"};
  return {SealState::valid, ""};
}

std::string unsealed_message(const std::string& file_label) {
  return file_label + ": is not sealed (format version 3, written by fbprep before 0.6, or an HDF5 file rewritten by "
         "another program), so nothing shows it is undamaged; check it and convert it once with: fbprep seal " +
         file_label;
}

std::string damaged_message(const std::string& file_label, const std::string& problem) {
  return file_label + ": damaged or modified after it was written: " + problem +
         "; if it was edited on purpose, check and re-seal it with: fbprep seal " + file_label;
}

}  // namespace flexbody::format::detail

namespace flexbody::format {

bool begins_like_body_file(const std::filesystem::path& path) {
  const detail::FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) return false;
  std::array<char, detail::kMagicLine.size()> start{};
  const long long n = detail::read_at(fd.get(), start.data(), start.size(), 0);
  const std::string_view begins(start.data(), n < 0 ? 0 : static_cast<std::size_t>(n));
  return begins.starts_with(detail::kMagicLine) || begins.starts_with(detail::kHdf5Signature);
}

std::string recorded_sha256(const std::filesystem::path& path) {
  const detail::FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) return {};
  detail::Block block{};
  if (detail::read_at(fd.get(), block.data(), block.size(), 0) != static_cast<long long>(block.size())) return {};
  const std::optional<detail::Recorded> recorded = detail::parse_block(block);
  return recorded ? recorded->hex : std::string();
}

}  // namespace flexbody::format
