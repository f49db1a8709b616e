#include "vtu_read.hpp"

#include <cstring>

namespace flexbody::test {

std::vector<unsigned char> base64_decode(const std::string& text) {
  static const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<unsigned char> out;
  std::uint32_t buffer = 0;
  int bits = 0;
  for (char c : text) {
    if (c == '=') break;
    const auto value = alphabet.find(c);
    if (value == std::string::npos) continue;
    buffer = (buffer << 6) | static_cast<std::uint32_t>(value);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((buffer >> bits) & 0xFF));
    }
  }
  return out;
}

std::string vtu_array(const std::string& vtu, const std::string& name) {
  const auto at = vtu.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return "";
  const auto begin = vtu.find('>', at) + 1;
  return vtu.substr(begin, vtu.find("</DataArray>", begin) - begin);
}

template <class T>
std::vector<T> vtu_values(const std::string& vtu, const std::string& name) {
  const std::vector<unsigned char> bytes = base64_decode(vtu_array(vtu, name));
  if (bytes.size() < 8) return {};
  std::uint64_t length = 0;
  std::memcpy(&length, bytes.data(), 8);
  if (length != bytes.size() - 8 || length % sizeof(T) != 0) return {};
  std::vector<T> values(length / sizeof(T));
  std::memcpy(values.data(), bytes.data() + 8, length);
  return values;
}

template std::vector<double> vtu_values<double>(const std::string&, const std::string&);
template std::vector<std::int64_t> vtu_values<std::int64_t>(const std::string&, const std::string&);

}  // namespace flexbody::test
