// file_digest.cpp: sha256_of_file() (flexbody/format/file_digest.hpp).
#include "flexbody/format/file_digest.hpp"

#include "sha256.hpp"

#include <array>
#include <cstdint>
#include <fstream>
#include <stdexcept>

namespace flexbody::format {

std::string sha256_of_file(const std::filesystem::path& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
    throw std::runtime_error(path.string() + ": is a directory, not a file to take the SHA-256 of");
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error(path.string() + ": cannot be opened for reading");
  detail::Sha256 hash;
  std::array<char, 1 << 16> buffer{};
  while (file.read(buffer.data(), buffer.size()) || file.gcount() > 0) {
    hash.update({reinterpret_cast<const std::uint8_t*>(buffer.data()), static_cast<std::size_t>(file.gcount())});
    if (!file) break;  // the last, partial block
  }
  if (file.bad()) throw std::runtime_error(path.string() + ": could not be read to its end");
  return detail::to_hex(hash.finish());
}

}  // namespace flexbody::format
