// checkpoint_file.cpp: write_checkpoint_file() and read_checkpoint_file() (checkpoint_file.hpp, SCHEMA.md
// "Checkpoint file"), on the body files' HDF5 layer, seal and structure check.
#include "flexbody/format/checkpoint_file.hpp"

#include "body_file_seal.hpp"
#include "file_image.hpp"
#include "hdf5_io.hpp"
#include "hdf5_structure.hpp"
#include "sealed_write.hpp"
#include "sha256.hpp"

#include "flexbody/format/body_file.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <stdexcept>
#include <string_view>

namespace flexbody::format {
namespace {

using detail::Location;

constexpr std::size_t kLongestName = 200;

bool valid_name(std::string_view name) {
  const auto allowed = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
  };
  return !name.empty() && name.size() <= kLongestName && name != "." && name != ".." &&
         std::all_of(name.begin(), name.end(), allowed);
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm parts{};
  gmtime_r(&now, &parts);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &parts);
  return text;
}

}  // namespace

std::string sha256_hex(std::string_view bytes) {
  detail::Sha256 hash;
  hash.update({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()});
  return detail::to_hex(hash.finish());
}

void write_checkpoint_file(const CheckpointData& checkpoint, const std::filesystem::path& path) {
  for (const auto& [name, values] : checkpoint.numbers) {
    if (!valid_name(name)) throw std::invalid_argument("checkpoint: the entry name '" + name + "' is not allowed");
    if (!std::all_of(values.begin(), values.end(), [](double x) { return std::isfinite(x); }))
      throw std::invalid_argument("checkpoint: the entry '" + name + "' holds a value that is not finite");
  }
  for (const auto& entry : checkpoint.texts)
    if (!valid_name(entry.first)) throw std::invalid_argument("checkpoint: the entry name '" + entry.first + "' is not allowed");
  if (!std::isfinite(checkpoint.time)) throw std::invalid_argument("checkpoint: the time is not finite");
  detail::write_sealed_file(path, path.string(), [&checkpoint](const Location& file) {
    detail::write_string_attribute(file, "format", kCheckpointFormatName);
    detail::write_int_attribute(file, "format_version", kCheckpointFormatVersion);
    detail::write_string_attribute(file, "created_by", checkpoint.created_by);
    detail::write_string_attribute(file, "created_utc", utc_now());
    detail::write_double_attribute(file, "time", checkpoint.time);
    const Location numbers = detail::create_group(file, "numbers");
    for (const auto& [name, values] : checkpoint.numbers) detail::write_vector(numbers, name, values, "");
    const Location texts = detail::create_group(file, "texts");
    for (const auto& [name, text] : checkpoint.texts) detail::write_byte_vector(texts, name, text);
  });
}

CheckpointData read_checkpoint_file(const std::filesystem::path& path) {
  const std::string label = path.string();
  std::vector<char> image = detail::read_file_image(path, label);
  const std::string_view bytes(image.data(), image.size());
  const detail::SealCheck seal = detail::check_seal(bytes);
  if (seal.state == detail::SealState::damaged)
    throw BodyFileDamaged(label + ": damaged or modified after it was written: " + seal.problem +
                          "; a checkpoint cannot be repaired: resume from an earlier copy or run again");
  if (!detail::is_hdf5_file(bytes)) throw BodyFileError(label + ": not a checkpoint (not an HDF5 file)");
  if (seal.state == detail::SealState::absent)
    throw BodyFileError(label + ": not a checkpoint (it has no flexbody seal; fbsim writes checkpoints sealed)");
  const std::string problem = detail::check_hdf5_structure(bytes, detail::kSealBytes);
  if (!problem.empty())
    throw BodyFileError(label + ": its HDF5 structure is not what fbsim writes (" + problem + ")");
  const detail::QuietHdf5Errors quiet;
  const Location file = detail::open_file_image(image, label, false);
  if (!detail::has_attribute(file, "/", "format") ||
      detail::read_string_attribute(file, "format") != kCheckpointFormatName) {
    const bool body = detail::has_attribute(file, "/", "format") && detail::read_string_attribute(file, "format") == kFormatName;
    file.fail(body ? "is a body file, not a checkpoint" : "not a checkpoint (its /format is not \"flexbody checkpoint\")");
  }
  const int version = detail::read_int_attribute(file, "format_version");
  if (version != kCheckpointFormatVersion)
    file.fail("checkpoint format version " + std::to_string(version) + "; this fbsim reads version " +
              std::to_string(kCheckpointFormatVersion));
  CheckpointData data;
  data.created_by = detail::read_string_attribute(file, "created_by");
  data.time = detail::read_double_attribute(file, "time");
  if (!std::isfinite(data.time)) file.fail("/time is not finite");
  const Location numbers = detail::open_group(file, "numbers");
  for (const std::string& name : detail::member_names(numbers)) {
    std::vector<double> values = detail::read_double_vector(numbers, name);
    if (!std::all_of(values.begin(), values.end(), [](double x) { return std::isfinite(x); }))
      file.fail(numbers.child(name) + " holds a value that is not finite");
    data.numbers.emplace(name, std::move(values));
  }
  const Location texts = detail::open_group(file, "texts");
  for (const std::string& name : detail::member_names(texts)) data.texts.emplace(name, detail::read_byte_vector(texts, name));
  return data;
}

}  // namespace flexbody::format
