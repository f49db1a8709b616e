#pragma once
// Reading back what the VTK XML writers wrote (base64 binary arrays with UInt64 headers), for assertions.

#include <cstdint>
#include <string>
#include <vector>

namespace flexbody::test {

/// The raw bytes of a base64 text (padding and whitespace ignored).
[[nodiscard]] std::vector<unsigned char> base64_decode(const std::string& text);

/// The base64 text of the DataArray named `name` in a .vtu file's text ("" if there is none).
[[nodiscard]] std::string vtu_array(const std::string& vtu, const std::string& name);

/// The values of a Float64 (or, with T = std::int64_t, Int64) DataArray: its bytes after the 8-byte length
/// header. Empty if the array is missing or its header disagrees with its length.
template <class T>
[[nodiscard]] std::vector<T> vtu_values(const std::string& vtu, const std::string& name);

}  // namespace flexbody::test
