#pragma once
// sha256.hpp (private): SHA-256 (FIPS 180-4), for the body file's integrity seal (body_file_seal.cpp).
// Written here because flexbody::format depends on Eigen and HDF5 only (ARCHITECTURE.md); a Python
// user checks the same digest with hashlib.sha256.
//
// \code
//   Sha256 hash;
//   hash.update(bytes);            // any number of times, any lengths
//   std::string hex = to_hex(hash.finish());
// \endcode

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace flexbody::format::detail {

class Sha256 {
 public:
  using Digest = std::array<std::uint8_t, 32>;

  Sha256() noexcept;
  /// Appends `bytes` to the message.
  void update(std::span<const std::uint8_t> bytes) noexcept;
  /// Pads the message and returns its digest; the object then starts a new, empty message.
  [[nodiscard]] Digest finish() noexcept;

 private:
  void compress(const std::uint8_t* block) noexcept;

  std::array<std::uint32_t, 8> state_{};
  std::array<std::uint8_t, 64> buffer_{};
  std::size_t buffered_ = 0;     ///< bytes waiting in buffer_ (< 64)
  std::uint64_t length_ = 0;     ///< message length so far, in bytes
};

/// Lowercase hexadecimal, two characters per byte (what hashlib's hexdigest() prints).
[[nodiscard]] std::string to_hex(const Sha256::Digest& digest);

}  // namespace flexbody::format::detail
