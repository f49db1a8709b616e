#include "flexbody/format/vtk_xml.hpp"

#include <charconv>
#include <cmath>
#include <cstring>
#include <string_view>
#include <stdexcept>
#include <unistd.h>

namespace flexbody::format {
namespace {

// Base64 of a VTK binary block: an 8-byte length header (header_type="UInt64") followed by the data.
std::string base64_block(const void* data, std::size_t bytes) {
  std::vector<unsigned char> raw(8 + bytes);
  const std::uint64_t length = bytes;
  std::memcpy(raw.data(), &length, 8);
  if (bytes > 0) std::memcpy(raw.data() + 8, data, bytes);
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((raw.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < raw.size(); i += 3) {
    const std::uint32_t a = raw[i], b = i + 1 < raw.size() ? raw[i + 1] : 0, c = i + 2 < raw.size() ? raw[i + 2] : 0;
    const std::uint32_t triple = (a << 16) | (b << 8) | c;
    out += kAlphabet[(triple >> 18) & 63];
    out += kAlphabet[(triple >> 12) & 63];
    out += i + 1 < raw.size() ? kAlphabet[(triple >> 6) & 63] : '=';
    out += i + 2 < raw.size() ? kAlphabet[triple & 63] : '=';
  }
  return out;
}

std::filesystem::path temporary_beside(const std::filesystem::path& path) {
  std::string name = ".";  // appended, not "." + ...: GCC 12 warns falsely (-Wrestrict) on the temporary
  name += path.filename().string();
  name += ".tmp-";
  name += std::to_string(::getpid());
  return path.parent_path() / name;
}

// XML attribute text: names come from users (scene and body spec names).
std::string escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

}  // namespace

VtuWriter::VtuWriter(std::filesystem::path path, std::int64_t points, std::int64_t cells)
    : path_(std::move(path)), temporary_(temporary_beside(path_)), points_(points), cells_(cells) {
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_) throw std::runtime_error(path_.string() + ": cannot be written");
  out_ << "<?xml version=\"1.0\"?>\n"
       << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
       << "  <UnstructuredGrid>\n"
       << "    <Piece NumberOfPoints=\"" << points_ << "\" NumberOfCells=\"" << cells_ << "\">\n";
}

VtuWriter::~VtuWriter() {
  if (stage_ == Stage::done) return;
  out_.close();
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
}

void VtuWriter::array(const char* type, const std::string& name, int components, const void* data,
                      std::size_t bytes) {
  out_ << "        <DataArray type=\"" << type << "\" Name=\"" << escaped(name) << "\" NumberOfComponents=\""
       << components << "\" format=\"binary\">\n          " << base64_block(data, bytes) << "\n        </DataArray>\n";
}

void VtuWriter::check_count(const std::string& name, int components, std::size_t count) const {
  if (count != static_cast<std::size_t>(components) * static_cast<std::size_t>(points_))
    throw std::logic_error(path_.string() + ": array " + name + " has " + std::to_string(count) + " values for " +
                           std::to_string(points_) + " points of " + std::to_string(components) + " components");
}

void VtuWriter::point_array(const std::string& name, int components, const std::vector<double>& values) {
  if (stage_ != Stage::point_data) throw std::logic_error(path_.string() + ": point data after the points");
  check_count(name, components, values.size());
  for (const double v : values)
    if (!std::isfinite(v)) throw std::runtime_error(path_.string() + ": array " + name + " holds a non-finite value");
  if (!point_data_open_) out_ << "      <PointData>\n";
  point_data_open_ = true;
  array("Float64", name, components, values.data(), values.size() * sizeof(double));
}

void VtuWriter::point_array(const std::string& name, const std::vector<std::int32_t>& values) {
  if (stage_ != Stage::point_data) throw std::logic_error(path_.string() + ": point data after the points");
  check_count(name, 1, values.size());
  if (!point_data_open_) out_ << "      <PointData>\n";
  point_data_open_ = true;
  array("Int32", name, 1, values.data(), values.size() * sizeof(std::int32_t));
}

void VtuWriter::close_point_data() {
  if (point_data_open_) out_ << "      </PointData>\n";
  point_data_open_ = false;
}

void VtuWriter::points(const std::vector<double>& xyz) {
  if (stage_ != Stage::point_data) throw std::logic_error(path_.string() + ": points written twice");
  check_count("Points", 3, xyz.size());
  for (const double v : xyz)
    if (!std::isfinite(v)) throw std::runtime_error(path_.string() + ": a point coordinate is not finite");
  close_point_data();
  out_ << "      <Points>\n";
  array("Float64", "Points", 3, xyz.data(), xyz.size() * sizeof(double));
  out_ << "      </Points>\n";
  stage_ = Stage::cells;
}

void VtuWriter::cells(const std::vector<std::int64_t>& connectivity, int nodes_per_cell, std::uint8_t vtk_type) {
  if (stage_ != Stage::cells) throw std::logic_error(path_.string() + ": cells before the points, or twice");
  if (connectivity.size() != static_cast<std::size_t>(cells_) * static_cast<std::size_t>(nodes_per_cell))
    throw std::logic_error(path_.string() + ": " + std::to_string(connectivity.size()) + " cell indices for " +
                           std::to_string(cells_) + " cells of " + std::to_string(nodes_per_cell) + " nodes");
  for (const std::int64_t i : connectivity)
    if (i < 0 || i >= points_) throw std::logic_error(path_.string() + ": a cell names point " + std::to_string(i));
  std::vector<std::int64_t> offsets(static_cast<std::size_t>(cells_));
  for (std::size_t e = 0; e < offsets.size(); ++e) offsets[e] = static_cast<std::int64_t>(nodes_per_cell * (e + 1));
  const std::vector<std::uint8_t> types(static_cast<std::size_t>(cells_), vtk_type);
  out_ << "      <Cells>\n";
  array("Int64", "connectivity", 1, connectivity.data(), connectivity.size() * sizeof(std::int64_t));
  array("Int64", "offsets", 1, offsets.data(), offsets.size() * sizeof(std::int64_t));
  array("UInt8", "types", 1, types.data(), types.size());
  out_ << "      </Cells>\n";
  stage_ = Stage::closing;
}

void VtuWriter::commit() {
  if (stage_ != Stage::closing) throw std::logic_error(path_.string() + ": commit before the points and cells");
  out_ << "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  out_.close();
  if (!out_) throw std::runtime_error(path_.string() + ": writing failed (disk full?)");
  std::filesystem::rename(temporary_, path_);
  stage_ = Stage::done;
}

void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& steps) {
  const std::filesystem::path temporary = temporary_beside(path);
  try {
    std::ofstream out(temporary, std::ios::trunc);
    if (!out) throw std::runtime_error(path.string() + ": cannot be written");
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
        << "  <Collection>\n";
    for (const auto& [time, file] : steps) {
      char text[32];  // the shortest text that reads back as the same double
      const auto end = std::to_chars(text, text + sizeof text, time).ptr;
      out << "    <DataSet timestep=\"" << std::string_view(text, static_cast<std::size_t>(end - text))
          << "\" part=\"0\" file=\"" << escaped(file) << "\"/>\n";
    }
    out << "  </Collection>\n</VTKFile>\n";
    out.close();
    if (!out) throw std::runtime_error(path.string() + ": writing failed (disk full?)");
    std::filesystem::rename(temporary, path);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
}

}  // namespace flexbody::format
