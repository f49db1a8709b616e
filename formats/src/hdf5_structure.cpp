// hdf5_structure.cpp: check_hdf5_structure() (hdf5_structure.hpp). Layouts from the HDF5 File Format Specification
// version 3.0: superblock version 2 (section II.A), version-2 object headers and continuation chunks (IV.A.1.b), and
// the header messages Link Info (0x0002), Link (0x0006), Attribute (0x000C), Object Header Continuation (0x0010) and
// Attribute Info (0x0015). All integers are little-endian; offsets and lengths are 8 bytes (checked in the
// superblock), and addresses are relative to the superblock's base address.
#include "hdf5_structure.hpp"

#include <algorithm>
#include <cstdint>
#include <exception>
#include <set>
#include <vector>

namespace flexbody::format::detail {
namespace {

constexpr std::uint64_t kUndefined = ~std::uint64_t{0};
constexpr std::size_t kMaxObjects = 100000;  // objects (and chunks) a body file may hold; kMaxLinks in hdf5_io.hpp
constexpr std::string_view kSuperblockSignature{"\x89HDF\r\n\x1a\n", 8};
constexpr int kMaxDepth = 8;                     // groups below the root (fbprep's files: 3)
constexpr std::uint64_t kMaxStringType = 65535;   // a string attribute in an object header holds less
constexpr std::uint64_t kMaxAttributeValues = 1 << 20;

// The messages fbprep's files hold: NIL (padding), dataspace, link info, datatype, fill value, link, data layout,
// group info, attribute, continuation, attribute info. A filter pipeline, an external file list, a shared message
// table or a modification time never appear in them.
constexpr bool kAllowedMessage[0x16] = {
    /*0x00 NIL*/ true,  /*0x01 dataspace*/ true, /*0x02 link info*/ true, /*0x03 datatype*/ true,
    /*0x04 old fill*/ false, /*0x05 fill value*/ true, /*0x06 link*/ true, /*0x07 external files*/ false,
    /*0x08 layout*/ true, /*0x09 bogus*/ false, /*0x0A group info*/ true, /*0x0B filters*/ false,
    /*0x0C attribute*/ true, /*0x0D comment*/ false, /*0x0E old time*/ false, /*0x0F shared table*/ false,
    /*0x10 continuation*/ true, /*0x11 symbol table*/ false, /*0x12 time*/ false, /*0x13 B-tree K*/ false,
    /*0x14 driver info*/ false, /*0x15 attribute info*/ true,
};

/// A failure of the walk: what is wrong, for the message.
struct Refusal {
  std::string what;
};

/// Bounds-checked little-endian reads from the file's bytes.
class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}
  [[nodiscard]] std::size_t size() const { return bytes_.size(); }
  [[nodiscard]] std::uint64_t uint(std::size_t at, std::size_t width) const {
    if (at > bytes_.size() || width > bytes_.size() - at)
      throw Refusal{"a structure at byte " + std::to_string(at) + " runs past the end of the file"};
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < width; ++i)
      value |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes_[at + i])) << (8 * i);
    return value;
  }
  [[nodiscard]] bool has(std::size_t at, std::string_view signature) const {
    return at <= bytes_.size() && bytes_.substr(at).starts_with(signature);
  }

 private:
  std::string_view bytes_;
};

class Walk {
 public:
  Walk(std::string_view bytes, std::size_t base) : file_(bytes), base_(base) {}

  void run() {
    if (!file_.has(base_, kSuperblockSignature)) throw Refusal{"no HDF5 superblock after the seal"};
    const std::uint64_t version = file_.uint(base_ + 8, 1);
    if (version != 2) throw Refusal{"superblock version " + std::to_string(version) + ", expected 2"};
    if (file_.uint(base_ + 9, 1) != 8 || file_.uint(base_ + 10, 1) != 8)
      throw Refusal{"the superblock's sizes of offsets and lengths are not 8 bytes"};
    if (file_.uint(base_ + 12, 8) != base_)
      throw Refusal{"the superblock's base address is not " + std::to_string(base_) + ", where it sits"};
    if (file_.uint(base_ + 20, 8) != kUndefined) throw Refusal{"the superblock has an extension"};
    // libhdf5 1.10 records the end of file counted from byte 0 of the file, user block included.
    const std::uint64_t end = file_.uint(base_ + 28, 8);
    if (end != file_.size())
      throw Refusal{"the superblock's end-of-file address " + std::to_string(end) + " is not the file's size " +
                    std::to_string(file_.size())};
    // A work list, not recursion: a crafted chain of groups or chunks cannot exhaust the stack.
    pending_.push_back({file_.uint(base_ + 36, 8), "/", 0});
    while (!pending_.empty()) {
      const Pending next = pending_.back();
      pending_.pop_back();
      depth_ = next.depth;
      object(next.address, next.path);
    }
  }

 private:
  /// The absolute position of address `address` of a structure of at least `length` bytes, or a refusal.
  std::size_t locate(std::uint64_t address, std::uint64_t length, const std::string& what) const {
    const std::uint64_t room = file_.size() - base_;
    if (address == kUndefined || address >= room || length > room - address)
      throw Refusal{what + " points to address " + (address == kUndefined ? "undefined" : std::to_string(address)) +
                    ", outside the file"};
    return base_ + static_cast<std::size_t>(address);
  }

  void count(const std::string& what) {
    if (++structures_ > kMaxObjects) throw Refusal{"more than " + std::to_string(kMaxObjects) + " objects (at " + what + ")"};
  }

  /// The object header at `address`, reached as HDF5 path `path`; the objects it links to join the work list.
  void object(std::uint64_t address, const std::string& path) {
    if (!objects_.insert(address).second) return;  // a second hard link to an object already checked
    const std::string header = "the object header of " + path;
    count(header);
    const std::size_t at = locate(address, 16, path);
    if (!file_.has(at, "OHDR") || file_.uint(at + 4, 1) != 2)
      throw Refusal{path + " points to address " + std::to_string(address) + ", where no version-2 object header is"};
    const auto flags = static_cast<unsigned>(file_.uint(at + 5, 1));
    if ((flags & 0xC0U) != 0) throw Refusal{header + " has reserved flags set"};
    std::size_t pos = at + 6 + ((flags & 0x20U) != 0 ? 16 : 0) + ((flags & 0x10U) != 0 ? 4 : 0);
    const std::size_t width = std::size_t{1} << (flags & 3U);
    const std::uint64_t size = file_.uint(pos, width);
    pos += width;
    // The messages, then a 4-byte checksum, must lie in the file; continuation chunks join the list as found.
    if (size > file_.size()) throw Refusal{header + " declares " + std::to_string(size) + " bytes of messages"};
    (void)locate(pos - base_, size + 4, header);
    chunk_list_.assign(1, {pos, pos + static_cast<std::size_t>(size)});
    for (std::size_t i = 0; i < chunk_list_.size(); ++i) {
      const Chunk chunk = chunk_list_[i];
      messages(chunk.begin, chunk.end, flags, path);
    }
  }

  /// The messages of one chunk [begin, end) of the object header of `path`, with `flags`.
  void messages(std::size_t begin, std::size_t end, unsigned flags, const std::string& path) {
    const std::string header = "the object header of " + path;
    const std::size_t head = (flags & 0x04U) != 0 ? 6 : 4;  // type, size, flags [, creation order]
    std::size_t pos = begin;
    while (end - pos >= head) {  // a gap shorter than a message header may end a chunk
      const auto type = static_cast<std::size_t>(file_.uint(pos, 1));
      const auto size = static_cast<std::size_t>(file_.uint(pos + 1, 2));
      const std::size_t body = pos + head;
      if (size > end - body)
        throw Refusal{header + " has a message of " + std::to_string(size) + " bytes that runs past its chunk"};
      if (type >= sizeof kAllowedMessage || !kAllowedMessage[type])
        throw Refusal{path + " holds an HDF5 message of type " + std::to_string(type) + message_name(type) +
                      ", which fbprep never writes"};
      // fbprep's messages are at most constant (bit 0) and not shareable (bit 2). A shared one (bit 1) makes libhdf5
      // read the message from another object header at any address (a review looped it into a stack overflow).
      if ((file_.uint(pos + 3, 1) & ~std::uint64_t{0x05}) != 0)
        throw Refusal{path + " holds a message of type " + std::to_string(type) + " with flags fbprep never sets (" +
                      std::to_string(file_.uint(pos + 3, 1)) + "; 2 would share it from another object)"};
      message(type, body, size, path);
      pos = body + size;
    }
  }

  void message(std::size_t type, std::size_t at, std::size_t size, const std::string& path) {
    const std::string header = "the object header of " + path;
    auto need = [&](std::size_t bytes) {
      if (bytes > size) throw Refusal{header + " has a message of type " + std::to_string(type) + " too short for its content"};
    };
    switch (type) {
      case 0x02:    // link info: version, flags, [max creation index], fractal heap, name B-tree, [order B-tree]
      case 0x15: {  // attribute info: the same with a 2-byte max creation index
        need(2);
        const auto info_flags = static_cast<unsigned>(file_.uint(at + 1, 1));
        const std::size_t index = (info_flags & 1U) != 0 ? (type == 0x02 ? 8 : 2) : 0;
        const std::size_t addresses = (info_flags & 2U) != 0 ? 3 : 2;
        need(2 + index + 8 * addresses);
        for (std::size_t k = 0; k < addresses; ++k) {
          const std::uint64_t address = file_.uint(at + 2 + index + 8 * k, 8);
          if (address != kUndefined)
            throw Refusal{path + " stores its " + (type == 0x02 ? "links" : "attributes") +
                          " densely (a heap or B-tree at " + std::to_string(address) +
                          "); fbprep keeps them in the object header"};
        }
        return;
      }
      case 0x01: dataspace(at, size, path); return;
      case 0x03: (void)datatype(at, size, path); return;
      case 0x05:  // fill value, version 3: flags only; a defined value (bit 5) is never written (libhdf5 converts it)
        if (size != 2 || file_.uint(at, 1) != 3 || (file_.uint(at + 1, 1) & 0xE0U) != 0)
          throw Refusal{path + " has a fill value message fbprep never writes (a defined fill value, or another form)"};
        return;
      case 0x08: layout(at, size, path); return;
      case 0x0A: {  // group info, version 0: flags, [max compact, min dense], [estimated entries, name length]
        need(2);
        const auto info_flags = static_cast<unsigned>(file_.uint(at + 1, 1));
        const std::size_t expected = 2 + ((info_flags & 1U) != 0 ? 4 : 0) + ((info_flags & 2U) != 0 ? 4 : 0);
        if (file_.uint(at, 1) != 0 || (info_flags & ~3U) != 0 || size != expected)
          throw Refusal{path + " has a malformed group info message"};
        return;
      }
      case 0x06: link(at, size, path); return;
      case 0x0C: attribute(at, size, path); return;
      case 0x10: {  // continuation: address and length of a chunk "OCHK", messages, checksum
        need(16);
        const std::uint64_t address = file_.uint(at, 8), length = file_.uint(at + 8, 8);
        const std::string what = header + "'s continuation";
        const std::size_t chunk = locate(address, length, what);
        if (length < 8 || !file_.has(chunk, "OCHK"))
          throw Refusal{what + " points to address " + std::to_string(address) + ", where no continuation chunk is"};
        if (!chunks_.insert(address).second) throw Refusal{what + " points to a chunk already read"};
        count(what);
        chunk_list_.push_back({chunk + 4, chunk + static_cast<std::size_t>(length) - 4});
        return;
      }
      default: return;  // NIL: padding
    }
  }

  /// Link message: version 1, flags, [type], [creation order], [charset], name length, name, and for a hard link
  /// the address of the object, which is checked next.
  void link(std::size_t at, std::size_t size, const std::string& parent) {
    std::string what = "a link in " + parent;
    std::size_t pos = at;
    auto take = [&](std::size_t bytes) {
      if (bytes > size - (pos - at)) throw Refusal{what + " is longer than its message"};
      const std::size_t here = pos;
      pos += bytes;
      return here;
    };
    if (file_.uint(take(1), 1) != 1) throw Refusal{what + " has a version other than 1"};
    const auto flags = static_cast<unsigned>(file_.uint(take(1), 1));
    if ((flags & 0xE0U) != 0) throw Refusal{what + " has reserved flags set"};
    const std::uint64_t type = (flags & 0x08U) != 0 ? file_.uint(take(1), 1) : 0;
    if ((flags & 0x04U) != 0) (void)take(8);
    if ((flags & 0x10U) != 0 && file_.uint(take(1), 1) > 1) throw Refusal{what + " has an unknown character set"};
    const std::size_t width = std::size_t{1} << (flags & 3U);
    const std::uint64_t length = file_.uint(take(width), width);
    if (length == 0 || length > size) throw Refusal{what + " has a name of " + std::to_string(length) + " bytes"};
    const std::string path = child(parent, text(take(static_cast<std::size_t>(length)), static_cast<std::size_t>(length)));
    if (type != 0) {
      throw Refusal{path + " is " + (type == 1 ? "a soft link" : type == 64 ? "an external link" : "a user-defined link") +
                    "; a body file holds hard links only"};
    }
    // fbprep's deepest object is /interfaces/NAME/rotation (depth 3); a crafted chain of thousands of groups
    // overflowed libhdf5's stack in its link walk.
    if (depth_ + 1 > kMaxDepth) throw Refusal{path + " lies deeper than " + std::to_string(kMaxDepth) + " groups"};
    pending_.push_back({file_.uint(take(8), 8), path, depth_ + 1});
  }

  /// Attribute message, version 3: version, flags (0: neither type nor space shared), name size, datatype size,
  /// dataspace size, charset, then the name, datatype, dataspace and data, each checked as its own message would be.
  void attribute(std::size_t at, std::size_t size, const std::string& object) {
    std::string what = "an attribute of " + object;
    if (size < 9) throw Refusal{what + " is shorter than its header"};
    if (file_.uint(at, 1) != 3 || file_.uint(at + 1, 1) != 0 || file_.uint(at + 8, 1) > 1)
      throw Refusal{what + " has a form fbprep never writes (version, shared parts or character set)"};
    const std::uint64_t name = file_.uint(at + 2, 2), type = file_.uint(at + 4, 2), space = file_.uint(at + 6, 2);
    if (name == 0 || 9 + name + type + space > size) throw Refusal{what + " declares parts longer than its message"};
    what = child(object, text(at + 9, static_cast<std::size_t>(name - 1)));  // the name ends in a NUL
    const std::size_t type_at = at + 9 + static_cast<std::size_t>(name);
    const std::uint64_t element = datatype(type_at, static_cast<std::size_t>(type), what);
    const std::uint64_t points = dataspace(type_at + type, static_cast<std::size_t>(space), what);
    if (points > kMaxAttributeValues || element * points > size - (9 + name + type + space))
      throw Refusal{what + " declares more values than its message holds"};
  }

  /// Datatype message (also inside an attribute): version 1, fixed-point (class 0), floating-point (1) or a
  /// fixed-length string (3) with exactly their properties. A variable-length type (class 9) keeps its values in the
  /// global heap. Returns the size of one element.
  std::uint64_t datatype(std::size_t at, std::size_t size, const std::string& path) {
    if (size < 8) throw Refusal{path + " has a datatype shorter than its header"};
    const auto version_class = static_cast<unsigned>(file_.uint(at, 1));
    const unsigned type_class = version_class & 0x0FU;
    const std::uint64_t element = file_.uint(at + 4, 4);
    if (type_class == 9)
      throw Refusal{path + " is a variable-length string (or sequence), whose values live in the global heap; a sealed "
                    "body file holds fixed-length strings only"};
    const std::size_t properties = type_class == 0 ? 4 : type_class == 1 ? 12 : type_class == 3 ? 0 : 1000;
    if ((version_class >> 4) != 1 || properties == 1000 || size != 8 + properties || element == 0 ||
        element > (type_class == 3 ? kMaxStringType : 16))
      throw Refusal{path + " has a datatype fbprep never writes (class " + std::to_string(type_class) + ", " +
                    std::to_string(element) + " bytes)"};
    return element;
  }

  /// Dataspace message (also inside an attribute), version 2: scalar (rank 0) or simple of rank 1 or 2, with or
  /// without maximum dimensions. Returns the number of points (capped: the reader checks declared sizes itself).
  std::uint64_t dataspace(std::size_t at, std::size_t size, const std::string& path) {
    if (size < 4) throw Refusal{path + " has a dataspace shorter than its header"};
    const std::uint64_t rank = file_.uint(at + 1, 1), flags = file_.uint(at + 2, 1), kind = file_.uint(at + 3, 1);
    const bool well_formed = file_.uint(at, 1) == 2 && rank <= 2 && (flags & ~std::uint64_t{1}) == 0 &&
                             ((kind == 0 && rank == 0) || (kind == 1 && rank >= 1)) &&
                             size == 4 + 8 * rank * (1 + flags);
    if (!well_formed) throw Refusal{path + " has a dataspace fbprep never writes"};
    std::uint64_t points = 1;
    for (std::uint64_t d = 0; d < rank; ++d) {
      const std::uint64_t dim = file_.uint(at + 4 + 8 * d, 8);
      points = dim == 0 ? 0 : (points > kMaxAttributeValues / dim ? kMaxAttributeValues + 1 : points * dim);
    }
    return points;
  }

  /// Data layout message, version 3, contiguous (class 1): the address and size of the values, inside the file
  /// (or an undefined address: storage never allocated, which the reader refuses by its size). Compact, chunked and
  /// virtual layouts are never written (a virtual one makes libhdf5 read the global heap while opening the dataset).
  void layout(std::size_t at, std::size_t size, const std::string& path) {
    if (size != 18 || file_.uint(at, 1) != 3 || file_.uint(at + 1, 1) != 1)
      throw Refusal{path + " has a data layout fbprep never writes (only contiguous storage)"};
    const std::uint64_t address = file_.uint(at + 2, 8), bytes = file_.uint(at + 10, 8);
    if (address != kUndefined) (void)locate(address, bytes, path + "'s values");
  }

  struct Pending {
    std::uint64_t address;
    std::string path;
    int depth;  ///< 0 for the root group
  };

  /// `length` bytes at `at` as text for a message (BodyFileError makes control characters spaces), at most 200.
  [[nodiscard]] std::string text(std::size_t at, std::size_t length) const {
    std::string result;
    for (std::size_t i = 0; i < std::min<std::size_t>(length, 200); ++i) result += static_cast<char>(file_.uint(at + i, 1));
    return length > 200 ? result + "..." : result;
  }
  static std::string child(const std::string& parent, const std::string& name) {
    return parent == "/" ? "/" + name : parent + "/" + name;
  }
  static std::string message_name(std::size_t type) {
    switch (type) {
      case 0x07: return " (external storage)";
      case 0x0B: return " (a filter pipeline: compression)";
      case 0x11: return " (an old-style symbol table)";
      case 0x12: return " (a modification time)";
      default: return "";
    }
  }
  struct Chunk {
    std::size_t begin, end;
  };
  Reader file_;
  std::size_t base_;
  std::vector<Pending> pending_;    ///< objects linked to, not yet checked
  std::vector<Chunk> chunk_list_;   ///< the chunks of the object header being checked
  std::set<std::uint64_t> objects_, chunks_;
  std::size_t structures_ = 0;
  int depth_ = 0;  ///< of the object header being checked
};

}  // namespace

std::string check_hdf5_structure(std::string_view bytes, std::size_t base) {
  try {
    Walk(bytes, base).run();
  } catch (const Refusal& refusal) {
    return refusal.what;
  } catch (const std::exception& error) {  // bad_alloc on a crafted structure: refused, never escaping
    return std::string("its structure cannot be checked (") + error.what() + ")";
  }
  return "";
}

}  // namespace flexbody::format::detail
