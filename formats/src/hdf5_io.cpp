// hdf5_io.cpp: handles, error capture, files and groups of the private HDF5 layer (attributes are in
// hdf5_attributes.cpp, datasets in hdf5_datasets.cpp).
#include "hdf5_io.hpp"

#include "flexbody/format/body_file.hpp"

#include <hdf5_hl.h>


namespace flexbody::format::detail {

Handle::Handle(Handle&& other) noexcept : id_(other.id_), closer_(other.closer_) {
  other.id_ = H5I_INVALID_HID;
}

Handle& Handle::operator=(Handle&& other) noexcept {
  if (this != &other) {
    (void)close();
    id_ = other.id_;
    closer_ = other.closer_;
    other.id_ = H5I_INVALID_HID;
  }
  return *this;
}

bool Handle::close() noexcept {
  if (id_ < 0 || closer_ == nullptr) return true;
  const herr_t status = closer_(id_);
  id_ = H5I_INVALID_HID;
  return status >= 0;
}

QuietHdf5Errors::QuietHdf5Errors() noexcept {
  if (H5Eget_auto2(H5E_DEFAULT, &function_, &data_) < 0) {
    function_ = nullptr;
    data_ = nullptr;
  }
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

QuietHdf5Errors::~QuietHdf5Errors() { H5Eset_auto2(H5E_DEFAULT, function_, data_); }

namespace {

herr_t keep_innermost(unsigned /*n*/, const H5E_error2_t* error, void* client_data) {
  if (error != nullptr && error->desc != nullptr && error->desc[0] != '\0') {
    *static_cast<std::string*>(client_data) = error->desc;
  }
  return 0;
}

/// File access properties; file locking is kept but not required (network file systems lack it).
Handle file_access(const Location& context) {
  Handle access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (!access.valid()) context.fail_hdf5("cannot create file access properties");
#if H5_VERSION_GE(1, 10, 7)
  if (H5Pset_file_locking(access.id(), true, true) < 0) context.fail_hdf5("cannot set up file locking");
#endif
  return access;
}

/// Keeps a group's links and attributes in its object header however many there are (HDF5 moves more than 8 into a
/// fractal heap and B-tree by default): readers refuse those structures in a sealed file (hdf5_structure.hpp).
bool keep_compact(hid_t creation) {
  constexpr unsigned kMany = 65535;  // the largest count HDF5 accepts
  return H5Pset_attr_phase_change(creation, kMany, kMany) >= 0 && H5Pset_link_phase_change(creation, kMany, kMany) >= 0;
}

}  // namespace

std::string hdf5_error_detail() {
  std::string innermost;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, keep_innermost, &innermost);
  return innermost;
}

std::string Location::child(std::string_view name) const {
  std::string result = path_;
  if (result.empty() || result.back() != '/') result += '/';
  result += name;
  return result;
}

void Location::fail(const std::string& message) const { throw BodyFileError(file_label_ + ": " + message); }

void Location::fail_hdf5(const std::string& message) const {
  const std::string detail = hdf5_error_detail();
  fail(detail.empty() ? message : message + " (HDF5: " + detail + ")");
}

void Location::close() {
  if (!handle_.close()) fail_hdf5("cannot close " + path_);
}

Location create_file(const std::filesystem::path& path, const std::string& file_label, std::size_t user_block_bytes) {
  const Location context(Handle(), file_label, "/");
  const Handle access = file_access(context);
  if (H5Pset_libver_bounds(access.id(), H5F_LIBVER_V18, H5F_LIBVER_V18) < 0 ||
      H5Pset_fclose_degree(access.id(), H5F_CLOSE_SEMI) < 0) {
    context.fail_hdf5("cannot set up file access properties");
  }
  Handle creation(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
  if (!creation.valid() || (user_block_bytes > 0 && H5Pset_userblock(creation.id(), user_block_bytes) < 0) ||
      !keep_compact(creation.id())) {
    context.fail_hdf5("cannot set up file creation properties");
  }
  Handle file(H5Fcreate(path.string().c_str(), H5F_ACC_EXCL, creation.id(), access.id()), H5Fclose);
  if (!file.valid()) context.fail_hdf5("cannot create the file " + path.string());
  return {std::move(file), file_label, "/"};
}

bool is_hdf5_file(std::string_view bytes) {
  // The superblock signature sits at byte 0 or, after a user block, at 512, 1024, 2048, ...
  static constexpr std::string_view kSignature{"\x89HDF\r\n\x1a\n", 8};
  for (std::size_t offset = 0; offset + kSignature.size() <= bytes.size(); offset = offset == 0 ? 512 : 2 * offset)
    if (bytes.substr(offset, kSignature.size()) == kSignature) return true;
  return false;
}

namespace {

struct LinkWalk {
  std::size_t links = 0;
  std::string refused;  ///< "<path> is a soft link", empty while every link is a hard one
};

herr_t check_link(hid_t /*group*/, const char* name, const H5L_info_t* info, void* data) {
  auto& walk = *static_cast<LinkWalk*>(data);
  if (info->type != H5L_TYPE_HARD) {
    const char* kind = info->type == H5L_TYPE_SOFT ? "a soft link" : info->type == H5L_TYPE_EXTERNAL ? "an external link"
                                                                                                    : "a user-defined link";
    walk.refused = std::string("/") + name + " is " + kind + "; a body file holds hard links only";
    return 1;
  }
  if (++walk.links > kMaxLinks) {
    walk.refused = "it holds more than " + std::to_string(kMaxLinks) + " links (objects), far more than a body file";
    return 1;
  }
  return 0;
}

}  // namespace

Location open_file_image(std::vector<char>& bytes, const std::string& file_label, bool variable_strings) {
  const Location context(Handle(), file_label, "/");
  // HDF5's core driver on the caller's buffer, not copied, never written, not freed by HDF5.
  Handle file(H5LTopen_file_image(bytes.data(), bytes.size(), H5LT_FILE_IMAGE_DONT_COPY | H5LT_FILE_IMAGE_DONT_RELEASE),
              H5Fclose);
  if (!file.valid()) context.fail_hdf5("cannot be opened although it is an HDF5 file; it may be truncated or damaged");
  // Before anything follows a link: visit every link once (HDF5 skips groups it has seen, so a cycle of hard links
  // ends), and refuse soft and external ones.
  LinkWalk walk;
  const herr_t status = H5Lvisit(file.id(), H5_INDEX_NAME, H5_ITER_NATIVE, check_link, &walk);
  if (!walk.refused.empty()) context.fail(walk.refused);
  if (status < 0) context.fail_hdf5("its groups cannot be listed; it may be damaged");
  return {std::move(file), file_label, "/", variable_strings};
}

void flush_and_close(Location& file) {
  if (H5Fflush(file.id(), H5F_SCOPE_GLOBAL) < 0) file.fail_hdf5("cannot flush the file to disk");
  file.close();
}

Location create_group(const Location& parent, std::string_view name) {
  const std::string key(name);
  const Handle creation(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
  if (!creation.valid() || !keep_compact(creation.id())) parent.fail_hdf5("cannot set up group creation properties");
  Handle group(H5Gcreate2(parent.id(), key.c_str(), H5P_DEFAULT, creation.id(), H5P_DEFAULT), H5Gclose);
  if (!group.valid()) parent.fail_hdf5("cannot create group " + parent.child(name));
  return {std::move(group), parent.file_label(), parent.child(name)};
}

namespace {

herr_t collect_name(hid_t /*group*/, const char* name, const H5L_info_t* /*info*/, void* data) {
  static_cast<std::vector<std::string>*>(data)->emplace_back(name);
  return 0;
}

}  // namespace

std::vector<std::string> member_names(const Location& group) {
  std::vector<std::string> names;
  hsize_t index = 0;
  if (H5Literate(group.id(), H5_INDEX_NAME, H5_ITER_INC, &index, collect_name, &names) < 0)
    group.fail_hdf5("cannot list the members of " + group.path());
  return names;
}

Location open_group(const Location& parent, std::string_view name) {
  const std::string key(name);
  if (H5Lexists(parent.id(), key.c_str(), H5P_DEFAULT) <= 0) parent.fail("missing group " + parent.child(name));
  Handle group(H5Gopen2(parent.id(), key.c_str(), H5P_DEFAULT), H5Gclose);
  if (!group.valid()) parent.fail_hdf5(parent.child(name) + " cannot be opened as a group");
  return {std::move(group), parent.file_label(), parent.child(name), parent.variable_strings_allowed()};
}

ObjectKind object_kind(const Location& file, const std::string& path) {
  if (H5Lexists(file.id(), path.c_str(), H5P_DEFAULT) <= 0) return ObjectKind::missing;
  const Handle object(H5Oopen(file.id(), path.c_str(), H5P_DEFAULT), H5Oclose);
  if (!object.valid()) return ObjectKind::other;
  switch (H5Iget_type(object.id())) {
    case H5I_GROUP: return ObjectKind::group;
    case H5I_DATASET: return ObjectKind::dataset;
    default: return ObjectKind::other;
  }
}

}  // namespace flexbody::format::detail

namespace flexbody::format {

// After a damaged file HDF5's own cleanup at exit can fail to close its internal objects and print "HDF5: infinite
// loop closing library" and a long line of codes (2,238 of 10,500 damaged files) after the tool's one
// error line. In the library this would change every HDF5 user of the process (a host program's own unclosed file
// came out damaged), so only the tools call it.
void skip_hdf5_cleanup_at_exit() { (void)H5dont_atexit(); }

}  // namespace flexbody::format
