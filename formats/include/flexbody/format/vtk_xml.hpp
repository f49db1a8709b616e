#pragma once
// flexbody/format/vtk_xml.hpp: ParaView's VTK XML files. A .vtu unstructured grid written as a stream (one
// array at a time, so a 1M-node body never holds all its arrays at once) and a .pvd collection that makes a
// time series of .vtu files. Arrays are base64-encoded binary with UInt64 length headers.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace flexbody::format {

/// VTK cell type numbers used here.
inline constexpr std::uint8_t kVtkTriangle = 5;
inline constexpr std::uint8_t kVtkTetra = 10;
/// VTK_QUADRATIC_TETRA: 10 nodes, corners then edges (0,1), (1,2), (2,0), (0,3), (1,3), (2,3), as the body file's.
inline constexpr std::uint8_t kVtkQuadraticTetra = 24;

/// One .vtu file, written in the order VTK expects: point arrays, then the points, then the cells, then
/// commit(). It is written to a temporary beside the target and renamed on commit(), so a failed or
/// abandoned write leaves nothing under the target's name. Calls out of order throw std::logic_error; a
/// write that fails throws std::runtime_error naming the file.
class VtuWriter {
 public:
  VtuWriter(std::filesystem::path path, std::int64_t points, std::int64_t cells);
  ~VtuWriter();  ///< removes the temporary unless committed
  VtuWriter(const VtuWriter&) = delete;
  VtuWriter& operator=(const VtuWriter&) = delete;

  /// A point array of `components` values per point (components × points values, point by point). A
  /// symmetric tensor is 6 components in ParaView's order XX, YY, ZZ, XY, YZ, XZ.
  void point_array(const std::string& name, int components, const std::vector<double>& values);
  void point_array(const std::string& name, const std::vector<std::int32_t>& values);
  /// The coordinates, x y z point by point [m].
  void points(const std::vector<double>& xyz);
  /// Cells of one type with `nodes_per_cell` 0-based point indices each, cell by cell.
  void cells(const std::vector<std::int64_t>& connectivity, int nodes_per_cell, std::uint8_t vtk_type);
  /// Closes the file and renames it into place.
  void commit();

 private:
  enum class Stage { point_data, cells, closing, done };
  void array(const char* type, const std::string& name, int components, const void* data, std::size_t bytes);
  void check_count(const std::string& name, int components, std::size_t count) const;
  void close_point_data();

  std::filesystem::path path_, temporary_;
  std::ofstream out_;
  std::int64_t points_, cells_;
  Stage stage_ = Stage::point_data;
  bool point_data_open_ = false;
};

/// Writes a ParaView collection (.pvd) of time steps, each (time [s], file relative to the .pvd), atomically.
void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& steps);

}  // namespace flexbody::format
