// hdf5_attributes.cpp: scalar, string and short-vector attributes of the private HDF5 layer.
#include "hdf5_io.hpp"

#include <initializer_list>
#include <limits>
#include <utility>

namespace flexbody::format::detail {
namespace {

std::string describe_class(H5T_class_t type_class) {
  switch (type_class) {
    case H5T_INTEGER: return "an integer";
    case H5T_FLOAT: return "a floating-point number";
    case H5T_STRING: return "a string";
    case H5T_COMPOUND: return "a compound";
    case H5T_ARRAY: return "an array";
    default: return "of HDF5 type class " + std::to_string(static_cast<int>(type_class));
  }
}

Handle open_attribute(const Location& loc, std::string_view name) {
  const std::string key(name);
  const htri_t exists = H5Aexists(loc.id(), key.c_str());
  if (exists == 0) loc.fail("missing attribute " + loc.child(name));
  if (exists < 0) loc.fail_hdf5("cannot look up attribute " + loc.child(name));
  Handle attribute(H5Aopen(loc.id(), key.c_str(), H5P_DEFAULT), H5Aclose);
  if (!attribute.valid()) loc.fail_hdf5("cannot open attribute " + loc.child(name));
  return attribute;
}

/// Type class of an attribute; throws unless it is one of `allowed` (listed in `expected`).
H5T_class_t attribute_class(const Location& loc, std::string_view name, const Handle& attribute,
                            std::initializer_list<H5T_class_t> allowed, const std::string& expected) {
  const Handle type(H5Aget_type(attribute.id()), H5Tclose);
  const H5T_class_t type_class = type.valid() ? H5Tget_class(type.id()) : H5T_NO_CLASS;
  for (const H5T_class_t ok : allowed) {
    if (type_class == ok) return type_class;
  }
  loc.fail(loc.child(name) + " is " + describe_class(type_class) + ", expected " + expected);
}

/// Number of elements of an attribute and its rank.
std::pair<hssize_t, int> attribute_extent(const Handle& attribute) {
  const Handle space(H5Aget_space(attribute.id()), H5Sclose);
  if (!space.valid()) return {-1, -1};
  return {H5Sget_simple_extent_npoints(space.id()), H5Sget_simple_extent_ndims(space.id())};
}

void require_scalar(const Location& loc, std::string_view name, const Handle& attribute) {
  const auto [count, rank] = attribute_extent(attribute);
  if (count != 1 || rank > 1) {
    loc.fail(loc.child(name) + " has " + std::to_string(count) + " values, expected a single value");
  }
}

void write_attribute(const Location& loc, std::string_view name, hid_t file_type, hid_t memory_type,
                     const Handle& space, const void* data) {
  const std::string key(name);
  const Handle attribute(H5Acreate2(loc.id(), key.c_str(), file_type, space.id(), H5P_DEFAULT, H5P_DEFAULT),
                         H5Aclose);
  if (!attribute.valid()) loc.fail_hdf5("cannot create attribute " + loc.child(name));
  if (H5Awrite(attribute.id(), memory_type, data) < 0) loc.fail_hdf5("cannot write attribute " + loc.child(name));
}

template <class T>
void write_scalar_attribute(const Location& loc, std::string_view name, hid_t file_type, hid_t memory_type,
                            T value) {
  const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  if (!space.valid()) loc.fail_hdf5("cannot create a dataspace for " + loc.child(name));
  write_attribute(loc, name, file_type, memory_type, space, &value);
}

}  // namespace

bool has_attribute(const Location& file, const std::string& object_path, std::string_view name) {
  const std::string key(name);
  const htri_t exists = H5Aexists_by_name(file.id(), object_path.c_str(), key.c_str(), H5P_DEFAULT);
  if (exists < 0) {
    file.fail_hdf5("cannot look up attribute " + (object_path == "/" ? "" : object_path) + "/" + key +
                   "; the file may be damaged");
  }
  return exists > 0;
}

void write_string_attribute(const Location& loc, std::string_view name, std::string_view value) {
  // HDF5 has no zero-size string type: "" is stored as one NUL byte, which reads back as "".
  // An attribute lives in its object header, whose messages hold less than 64 KiB; a longer string would go to
  // dense storage, which readers refuse in a sealed file (hdf5_structure.hpp).
  if (value.size() > kMaxWrittenStringBytes) {
    loc.fail(loc.child(name) + " would be a string of " + std::to_string(value.size()) + " bytes; a body file holds "
             "strings of at most " + std::to_string(kMaxWrittenStringBytes) + " bytes");
  }
  std::string text(value);
  if (text.empty()) text.push_back('\0');
  const Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!type.valid() || H5Tset_size(type.id(), text.size()) < 0 || H5Tset_strpad(type.id(), H5T_STR_NULLPAD) < 0 ||
      H5Tset_cset(type.id(), H5T_CSET_UTF8) < 0) {
    loc.fail_hdf5("cannot create a string type for " + loc.child(name));
  }
  const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  if (!space.valid()) loc.fail_hdf5("cannot create a dataspace for " + loc.child(name));
  write_attribute(loc, name, type.id(), type.id(), space, text.data());
}

void write_double_attribute(const Location& loc, std::string_view name, double value) {
  write_scalar_attribute(loc, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, value);
}

void write_int_attribute(const Location& loc, std::string_view name, int value) {
  write_scalar_attribute(loc, name, H5T_STD_I32LE, H5T_NATIVE_INT, value);
}

void write_double_vector_attribute(const Location& loc, std::string_view name, std::span<const double> values) {
  const hsize_t size = values.size();
  const Handle space(H5Screate_simple(1, &size, nullptr), H5Sclose);
  if (!space.valid()) loc.fail_hdf5("cannot create a dataspace for " + loc.child(name));
  write_attribute(loc, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, space, values.data());
}

std::string read_string_attribute(const Location& loc, std::string_view name) {
  const Handle attribute = open_attribute(loc, name);
  attribute_class(loc, name, attribute, {H5T_STRING}, "a string");
  require_scalar(loc, name, attribute);
  const Handle file_type(H5Aget_type(attribute.id()), H5Tclose);
  const Handle memory_type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!file_type.valid() || !memory_type.valid()) loc.fail_hdf5("cannot read the type of " + loc.child(name));
  const htri_t variable = H5Tis_variable_str(file_type.id());
  if (variable < 0) loc.fail_hdf5("cannot read the type of " + loc.child(name));
  if (variable > 0) {
    if (!loc.variable_strings_allowed()) {
      loc.fail(loc.child(name) + " is a variable-length string; a sealed body file holds fixed-length strings only "
               "(SCHEMA.md, \"Seal\")");
    }
    char* text = nullptr;
    if (H5Tset_size(memory_type.id(), H5T_VARIABLE) < 0 ||
        H5Tset_cset(memory_type.id(), H5Tget_cset(file_type.id())) < 0 ||
        H5Aread(attribute.id(), memory_type.id(), static_cast<void*>(&text)) < 0) {
      loc.fail_hdf5("cannot read attribute " + loc.child(name));
    }
    std::string result = text != nullptr ? text : "";
    H5free_memory(text);
    return result;
  }
  // The declared length is checked before a buffer is allocated for it: a damaged type may claim gigabytes.
  const std::size_t size = H5Tget_size(file_type.id());
  if (size == 0 || size > kMaxStringBytes || size > H5Aget_storage_size(attribute.id())) {
    loc.fail(loc.child(name) + " declares a string of " + std::to_string(size) + " bytes, but " +
             std::to_string(H5Aget_storage_size(attribute.id())) + " are stored (at most " +
             std::to_string(kMaxStringBytes) + " are accepted)");
  }
  std::vector<char> buffer(size + 1, '\0');
  if (H5Tset_size(memory_type.id(), size + 1) < 0 ||
      H5Tset_cset(memory_type.id(), H5Tget_cset(file_type.id())) < 0 ||
      H5Aread(attribute.id(), memory_type.id(), buffer.data()) < 0) {
    loc.fail_hdf5("cannot read attribute " + loc.child(name));
  }
  return std::string(buffer.data());
}

double read_double_attribute(const Location& loc, std::string_view name) {
  const Handle attribute = open_attribute(loc, name);
  attribute_class(loc, name, attribute, {H5T_FLOAT, H5T_INTEGER}, "a number");
  require_scalar(loc, name, attribute);
  double value = 0.0;
  if (H5Aread(attribute.id(), H5T_NATIVE_DOUBLE, &value) < 0) loc.fail_hdf5("cannot read attribute " + loc.child(name));
  return value;
}

int read_int_attribute(const Location& loc, std::string_view name) {
  const Handle attribute = open_attribute(loc, name);
  attribute_class(loc, name, attribute, {H5T_INTEGER}, "an integer");
  require_scalar(loc, name, attribute);
  // Read as 64 bits and range-checked here: HDF5 converts an int64 value beyond int's range to INT_MAX, which a
  // message would then report as the value found. (A value beyond 64 bits arrives clamped, still out of range.)
  long long value = 0;
  if (H5Aread(attribute.id(), H5T_NATIVE_LLONG, &value) < 0) loc.fail_hdf5("cannot read attribute " + loc.child(name));
  if (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max()) {
    loc.fail(loc.child(name) + " is " + std::to_string(value) + ", beyond the range of a 32-bit integer");
  }
  return static_cast<int>(value);
}

std::vector<double> read_double_vector_attribute(const Location& loc, std::string_view name, std::size_t size) {
  const Handle attribute = open_attribute(loc, name);
  attribute_class(loc, name, attribute, {H5T_FLOAT, H5T_INTEGER}, "numbers");
  const auto [count, rank] = attribute_extent(attribute);
  if (rank != 1 || count != static_cast<hssize_t>(size)) {
    loc.fail(loc.child(name) + " has " + std::to_string(count) + " values in " + std::to_string(rank) +
             " dimension(s), expected a 1-D list of " + std::to_string(size));
  }
  std::vector<double> values(size);
  if (H5Aread(attribute.id(), H5T_NATIVE_DOUBLE, values.data()) < 0) {
    loc.fail_hdf5("cannot read attribute " + loc.child(name));
  }
  return values;
}

}  // namespace flexbody::format::detail
