// body_file_error.cpp: BodyFileError's one-line, bounded message.
#include "flexbody/format/body_file.hpp"

namespace flexbody::format {
namespace {

std::string one_line(const std::string& message) {
  std::string line = message;
  for (char& c : line)
    if (static_cast<unsigned char>(c) < 0x20 || c == '\x7f') c = ' ';
  const std::size_t limit = BodyFileError::kMessageLimit;
  if (line.size() <= limit) return line;
  const std::string tail = " ... (" + std::to_string(line.size()) + " bytes, cut)";
  std::size_t keep = limit - tail.size();
  while (keep > 0 && (static_cast<unsigned char>(line[keep]) & 0xC0) == 0x80) --keep;  // not inside a UTF-8 character
  return line.substr(0, keep) + tail;
}

}  // namespace

BodyFileError::BodyFileError(const std::string& message) : std::runtime_error(one_line(message)) {}

}  // namespace flexbody::format
