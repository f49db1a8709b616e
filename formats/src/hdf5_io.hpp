#pragma once
// hdf5_io.hpp (private): a thin RAII layer over the HDF5 C API for the body file reader and writer,
// implemented in hdf5_io.cpp (handles, files, groups), hdf5_attributes.cpp and hdf5_datasets.cpp.
//
// Every failure becomes a BodyFileError whose message starts with the file's name and names the
// group, dataset or attribute concerned. Paths in messages are HDF5 paths; an attribute `a` of the
// object `/g` is written `/g/a` (and `/a` for a root attribute), as in SCHEMA.md.

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace flexbody::format::detail {

/// Owns one HDF5 identifier and releases it with the matching H5?close function.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);

  Handle() = default;
  Handle(hid_t id, Closer closer) noexcept : id_(id), closer_(closer) {}
  ~Handle() { (void)close(); }
  Handle(Handle&& other) noexcept;
  Handle& operator=(Handle&& other) noexcept;
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  [[nodiscard]] hid_t id() const noexcept { return id_; }
  [[nodiscard]] bool valid() const noexcept { return id_ >= 0; }
  /// Releases the identifier now; false if HDF5 reported an error while doing so.
  [[nodiscard]] bool close() noexcept;

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

/// Switches HDF5's automatic error printing off for its lifetime and restores it afterwards.
class QuietHdf5Errors {
 public:
  QuietHdf5Errors() noexcept;
  ~QuietHdf5Errors();
  QuietHdf5Errors(const QuietHdf5Errors&) = delete;
  QuietHdf5Errors& operator=(const QuietHdf5Errors&) = delete;

 private:
  H5E_auto2_t function_ = nullptr;
  void* data_ = nullptr;
};

/// The innermost description on this thread's HDF5 error stack (the most specific one), or "".
[[nodiscard]] std::string hdf5_error_detail();

/// An open file, group or dataset together with the names used in error messages.
class Location {
 public:
  Location(Handle handle, std::string file_label, std::string path, bool variable_strings = true)
      : handle_(std::move(handle)),
        file_label_(std::move(file_label)),
        path_(std::move(path)),
        variable_strings_(variable_strings) {}

  [[nodiscard]] hid_t id() const noexcept { return handle_.id(); }
  [[nodiscard]] const std::string& file_label() const noexcept { return file_label_; }
  /// HDF5 path of this object: "/" for the file, "/reduction" for a group.
  [[nodiscard]] const std::string& path() const noexcept { return path_; }
  /// Path of a member: "/reduction" and "upsilon" give "/reduction/upsilon"; "/" and "format" give "/format".
  [[nodiscard]] std::string child(std::string_view name) const;
  /// Throws BodyFileError("<file>: <message>").
  [[noreturn]] void fail(const std::string& message) const;
  /// Throws BodyFileError("<file>: <message> (HDF5: <innermost error>)").
  [[noreturn]] void fail_hdf5(const std::string& message) const;
  /// Closes the object now; throws if HDF5 reports an error (for the file: data not written).
  void close();
  /// Whether string attributes may be variable-length (they live in the file's global heap, whose damage crashed
  /// or hung libhdf5 1.10 in a fuzz run). Members opened from here inherit it.
  [[nodiscard]] bool variable_strings_allowed() const noexcept { return variable_strings_; }

 private:
  Handle handle_;
  std::string file_label_;
  std::string path_;
  bool variable_strings_ = true;
};

/// Creates a new file (fails if `path` exists); objects are laid out for HDF5 1.8 and later readers. The
/// HDF5 data starts after a user block of `user_block_bytes` (0, or a power of 2 from 512), which HDF5
/// leaves alone.
[[nodiscard]] Location create_file(const std::filesystem::path& path, const std::string& file_label,
                                   std::size_t user_block_bytes = 0);
/// True if a file's bytes carry the HDF5 signature (it may still be truncated or damaged).
[[nodiscard]] bool is_hdf5_file(std::string_view bytes);
/// Opens a file read-only from its bytes in memory (read_file_image), which must outlive the returned Location and
/// every object opened from it. Refuses a file with links other than hard links (a soft link may loop, an external
/// one opens another file) or more than kMaxLinks of them. `variable_strings`: see Location.
[[nodiscard]] Location open_file_image(std::vector<char>& bytes, const std::string& file_label, bool variable_strings);
/// Links a body file may hold (a current one has about 60, plus 7 per interface or output region).
inline constexpr std::size_t kMaxLinks = 100000;
/// Flushes and closes a file created by create_file; throws if either step fails.
void flush_and_close(Location& file);

[[nodiscard]] Location create_group(const Location& parent, std::string_view name);
/// The names of a group's members, in HDF5's name order.
[[nodiscard]] std::vector<std::string> member_names(const Location& group);
[[nodiscard]] Location open_group(const Location& parent, std::string_view name);

/// What a path inside a file refers to.
enum class ObjectKind { missing, group, dataset, other };
/// Kind of the object at absolute `path`; every parent group of `path` must exist.
[[nodiscard]] ObjectKind object_kind(const Location& file, const std::string& path);
/// True if the object at absolute `object_path` (which must exist) carries an attribute `name`; throws if HDF5
/// cannot tell (a damaged object header), rather than calling the attribute missing.
[[nodiscard]] bool has_attribute(const Location& file, const std::string& object_path, std::string_view name);

/// Writes a scalar string attribute: fixed-length UTF-8, NUL-padded (an empty string as one NUL byte), so that
/// the file needs no global heap (the heap variable-length strings live in; SCHEMA.md, "Seal").
void write_string_attribute(const Location& loc, std::string_view name, std::string_view value);
void write_double_attribute(const Location& loc, std::string_view name, double value);
void write_int_attribute(const Location& loc, std::string_view name, int value);
void write_double_vector_attribute(const Location& loc, std::string_view name,
                                   std::span<const double> values);

/// Longest string attribute written: it must fit one object-header message (less than 64 KiB).
inline constexpr std::size_t kMaxWrittenStringBytes = 65000;
/// Longest string attribute accepted (a source path or an option value is far shorter).
inline constexpr std::size_t kMaxStringBytes = std::size_t{1} << 20;
/// Reads a scalar string attribute: fixed-length, or variable-length where the Location allows it.
[[nodiscard]] std::string read_string_attribute(const Location& loc, std::string_view name);
/// Reads a scalar numeric attribute as double.
[[nodiscard]] double read_double_attribute(const Location& loc, std::string_view name);
/// Reads a scalar integer attribute.
[[nodiscard]] int read_int_attribute(const Location& loc, std::string_view name);
/// Reads a 1-D floating-point attribute of exactly `size` entries.
[[nodiscard]] std::vector<double> read_double_vector_attribute(const Location& loc, std::string_view name,
                                                               std::size_t size);

/// A 2-D dataset as read: shape and row-major values.
template <class T>
struct Table {
  std::size_t rows = 0;
  std::size_t cols = 0;
  std::vector<T> values;  ///< element (r, c) at r * cols + c
};

/// Writes a rows x cols dataset from row-major `data`; `unit` (if not empty) becomes its `unit` attribute.
void write_matrix(const Location& loc, std::string_view name, std::size_t rows, std::size_t cols,
                  const double* data, std::string_view unit);
void write_matrix(const Location& loc, std::string_view name, std::size_t rows, std::size_t cols,
                  const std::int32_t* data, std::string_view unit);
/// Writes a 1-D dataset.
void write_vector(const Location& loc, std::string_view name, std::span<const double> values,
                  std::string_view unit);

/// Writes a 1-D integer dataset.
void write_int_vector(const Location& loc, std::string_view name, std::span<const std::int32_t> values,
                      std::string_view unit);
/// Writes a 1-D dataset of bytes (u8): text that may exceed an attribute's 64 KiB, without a heap.
void write_byte_vector(const Location& loc, std::string_view name, std::string_view bytes);
/// Reads a 1-D dataset of bytes (an unsigned 8-bit integer dataset).
[[nodiscard]] std::string read_byte_vector(const Location& loc, std::string_view name);
/// Reads a 1-D integer dataset into int32 values.
[[nodiscard]] std::vector<std::int32_t> read_int_vector(const Location& loc, std::string_view name);
/// Reads a 2-D floating-point dataset.
[[nodiscard]] Table<double> read_double_matrix(const Location& loc, std::string_view name);
/// Reads a 2-D integer dataset into int32 values.
[[nodiscard]] Table<std::int32_t> read_int_matrix(const Location& loc, std::string_view name);
/// Reads a 1-D floating-point dataset.
[[nodiscard]] std::vector<double> read_double_vector(const Location& loc, std::string_view name);

}  // namespace flexbody::format::detail
