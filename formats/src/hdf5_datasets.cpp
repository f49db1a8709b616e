// hdf5_datasets.cpp: 1-D and 2-D datasets of the private HDF5 layer (row-major, contiguous).
#include "hdf5_io.hpp"

#include <array>
#include <cstddef>
#include <cstdio>
#include <limits>

namespace flexbody::format::detail {
namespace {

std::string shape_text(const std::vector<hsize_t>& dims) {
  std::string text;
  for (std::size_t i = 0; i < dims.size(); ++i) {
    if (i > 0) text += " x ";
    text += std::to_string(dims[i]);
  }
  return text.empty() ? "a scalar" : text;
}

void write_dataset(const Location& loc, std::string_view name, std::span<const hsize_t> dims, hid_t file_type,
                   hid_t memory_type, const void* data, std::string_view unit) {
  const std::string key(name);
  const Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  if (!space.valid()) loc.fail_hdf5("cannot create a dataspace for " + loc.child(name));
  Handle dataset(H5Dcreate2(loc.id(), key.c_str(), file_type, space.id(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                 H5Dclose);
  if (!dataset.valid()) loc.fail_hdf5("cannot create dataset " + loc.child(name));
  const bool empty = H5Sget_simple_extent_npoints(space.id()) == 0;
  if (!empty && H5Dwrite(dataset.id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    loc.fail_hdf5("cannot write dataset " + loc.child(name));
  }
  Location written(std::move(dataset), loc.file_label(), loc.child(name));
  if (!unit.empty()) write_string_attribute(written, "unit", unit);
  written.close();
}

/// An open dataset whose rank and type class have been checked.
struct OpenDataset {
  Handle dataset;
  std::vector<hsize_t> dims;
};

OpenDataset open_dataset(const Location& loc, std::string_view name, int rank, H5T_class_t type_class,
                         const char* expected_type) {
  const std::string key(name);
  if (H5Lexists(loc.id(), key.c_str(), H5P_DEFAULT) <= 0) loc.fail("missing dataset " + loc.child(name));
  OpenDataset result{Handle(H5Dopen2(loc.id(), key.c_str(), H5P_DEFAULT), H5Dclose), {}};
  if (!result.dataset.valid()) loc.fail_hdf5(loc.child(name) + " cannot be opened as a dataset");
  // The writer's layout only (SCHEMA.md, "Seal"): values stored in this file, in one piece, as written. A chunked
  // or filtered dataset would run decompression on bytes nobody checked, and external storage (or a virtual
  // dataset) reads other files, such as a FIFO that never answers or /dev/zero that never ends.
  const Handle creation(H5Dget_create_plist(result.dataset.id()), H5Pclose);
  if (!creation.valid()) loc.fail_hdf5("cannot read how " + loc.child(name) + " is stored");
  const H5D_layout_t layout = H5Pget_layout(creation.id());
  if (layout != H5D_CONTIGUOUS && layout != H5D_COMPACT) {
    const char* how = layout == H5D_CHUNKED   ? "in chunks"
                      : layout == H5D_VIRTUAL ? "as a virtual dataset"
                                              : "in an unknown layout";
    loc.fail(loc.child(name) + " is stored " + how + "; a body file's datasets are contiguous");
  }
  const int filters = H5Pget_nfilters(creation.id());
  const int external = H5Pget_external_count(creation.id());
  if (filters < 0 || external < 0) loc.fail_hdf5("cannot read how " + loc.child(name) + " is stored");
  if (filters > 0) loc.fail(loc.child(name) + " is compressed or filtered; a body file's datasets are not");
  if (external > 0) loc.fail(loc.child(name) + " keeps its values in external files; a body file holds them itself");

  const Handle type(H5Dget_type(result.dataset.id()), H5Tclose);
  if (!type.valid() || H5Tget_class(type.id()) != type_class) {
    loc.fail(loc.child(name) + " does not hold " + expected_type + " values");
  }
  const Handle space(H5Dget_space(result.dataset.id()), H5Sclose);
  const int found_rank = space.valid() ? H5Sget_simple_extent_ndims(space.id()) : -1;
  if (found_rank < 0) loc.fail_hdf5("cannot read the shape of " + loc.child(name));
  result.dims.assign(static_cast<std::size_t>(found_rank), 0);
  if (found_rank > 0 && H5Sget_simple_extent_dims(space.id(), result.dims.data(), nullptr) < 0) {
    loc.fail_hdf5("cannot read the shape of " + loc.child(name));
  }
  if (found_rank != rank) {
    loc.fail(loc.child(name) + " has shape " + shape_text(result.dims) + ", expected a " + std::to_string(rank) +
             "-D dataset");
  }
  return result;
}

std::string bytes_text(double bytes) {
  const char* units[] = {"bytes", "KB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 6) bytes /= 1000.0, ++u;
  char text[32];
  std::snprintf(text, sizeof text, u == 0 ? "%.0f %s" : "%.3g %s", bytes, units[u]);
  return text;
}

// The size a dataset declares, checked before anything is allocated for it (10^8 nodes declared in a
// 158 KB file took 4.7 GB and 8-18 s before the refusal): the schema's datasets are contiguous and uncompressed,
// so the values must fit in the file and in the storage HDF5 has allocated for them.
std::size_t checked_count(const Location& loc, std::string_view name, const OpenDataset& open, std::size_t memory_size) {
  double declared = 1.0;  // values, in floating point: the product of 64-bit dimensions may overflow an integer
  for (const hsize_t dim : open.dims) declared *= static_cast<double>(dim);
  const Handle type(H5Dget_type(open.dataset.id()), H5Tclose);
  const double stored_size = type.valid() ? static_cast<double>(H5Tget_size(type.id())) : 0.0;
  const Handle file(H5Iget_file_id(open.dataset.id()), H5Fclose);
  hsize_t file_size = 0;
  if (!file.valid() || H5Fget_filesize(file.id(), &file_size) < 0) loc.fail_hdf5("cannot read the file's size");
  const double storage = static_cast<double>(H5Dget_storage_size(open.dataset.id()));
  const double bytes = declared * stored_size;
  if (declared > 0.0 && (bytes > static_cast<double>(file_size) || bytes > storage))
    loc.fail(loc.child(name) + " declares " + shape_text(open.dims) + " values (" + bytes_text(bytes) + "), but " +
             (bytes > static_cast<double>(file_size) ? "the file has " + bytes_text(static_cast<double>(file_size))
                                                     : "only " + bytes_text(storage) + " of them are stored"));
  if (declared * static_cast<double>(memory_size) > static_cast<double>(std::numeric_limits<std::ptrdiff_t>::max()))
    loc.fail(loc.child(name) + " has an implausible shape " + shape_text(open.dims));
  return static_cast<std::size_t>(declared);
}

template <class T>
std::vector<T> read_values(const Location& loc, std::string_view name, const OpenDataset& open, hid_t memory_type) {
  const std::size_t count = checked_count(loc, name, open, sizeof(T));
  std::vector<T> values(count);
  if (count > 0 &&
      H5Dread(open.dataset.id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0) {
    loc.fail_hdf5("cannot read dataset " + loc.child(name));
  }
  return values;
}

template <class T>
Table<T> read_matrix(const Location& loc, std::string_view name, H5T_class_t type_class, const char* expected_type,
                     hid_t memory_type) {
  const OpenDataset open = open_dataset(loc, name, 2, type_class, expected_type);
  Table<T> table;
  table.values = read_values<T>(loc, name, open, memory_type);
  table.rows = static_cast<std::size_t>(open.dims[0]);
  table.cols = static_cast<std::size_t>(open.dims[1]);
  return table;
}

}  // namespace

void write_matrix(const Location& loc, std::string_view name, std::size_t rows, std::size_t cols,
                  const double* data, std::string_view unit) {
  const std::array<hsize_t, 2> dims{rows, cols};
  write_dataset(loc, name, dims, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, data, unit);
}

void write_matrix(const Location& loc, std::string_view name, std::size_t rows, std::size_t cols,
                  const std::int32_t* data, std::string_view unit) {
  const std::array<hsize_t, 2> dims{rows, cols};
  write_dataset(loc, name, dims, H5T_STD_I32LE, H5T_NATIVE_INT32, data, unit);
}

void write_vector(const Location& loc, std::string_view name, std::span<const double> values,
                  std::string_view unit) {
  const std::array<hsize_t, 1> dims{values.size()};
  write_dataset(loc, name, dims, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), unit);
}

void write_int_vector(const Location& loc, std::string_view name, std::span<const std::int32_t> values,
                      std::string_view unit) {
  const std::array<hsize_t, 1> dims{values.size()};
  write_dataset(loc, name, dims, H5T_STD_I32LE, H5T_NATIVE_INT32, values.data(), unit);
}

void write_byte_vector(const Location& loc, std::string_view name, std::string_view bytes) {
  const std::array<hsize_t, 1> dims{bytes.size()};
  write_dataset(loc, name, dims, H5T_STD_U8LE, H5T_NATIVE_UCHAR, bytes.data(), "");
}

std::string read_byte_vector(const Location& loc, std::string_view name) {
  const OpenDataset open = open_dataset(loc, name, 1, H5T_INTEGER, "byte");
  const Handle type(H5Dget_type(open.dataset.id()), H5Tclose);
  if (!type.valid() || H5Tget_size(type.id()) != 1) loc.fail(loc.child(name) + " does not hold bytes");
  const std::vector<unsigned char> values = read_values<unsigned char>(loc, name, open, H5T_NATIVE_UCHAR);
  return {values.begin(), values.end()};
}

Table<double> read_double_matrix(const Location& loc, std::string_view name) {
  return read_matrix<double>(loc, name, H5T_FLOAT, "floating-point", H5T_NATIVE_DOUBLE);
}

Table<std::int32_t> read_int_matrix(const Location& loc, std::string_view name) {
  return read_matrix<std::int32_t>(loc, name, H5T_INTEGER, "integer", H5T_NATIVE_INT32);
}

std::vector<double> read_double_vector(const Location& loc, std::string_view name) {
  const OpenDataset open = open_dataset(loc, name, 1, H5T_FLOAT, "floating-point");
  return read_values<double>(loc, name, open, H5T_NATIVE_DOUBLE);
}

std::vector<std::int32_t> read_int_vector(const Location& loc, std::string_view name) {
  const OpenDataset open = open_dataset(loc, name, 1, H5T_INTEGER, "integer");
  return read_values<std::int32_t>(loc, name, open, H5T_NATIVE_INT32);
}

}  // namespace flexbody::format::detail
