#pragma once
// hdf5_structure.hpp (private): a check of a sealed body file's HDF5 metadata, on its bytes, before libhdf5 parses
// them. A seal is a digest anyone can recompute, and so are HDF5's own checksums: a fuzz run changed bytes
// in object headers, recomputed both, and libhdf5 1.10 followed the changed addresses of dense link and attribute
// storage (and a changed link message) into segmentation faults. fbprep writes a small subset of HDF5 (superblock
// version 2, version-2 object headers, links and attributes stored compactly in them, no heaps), so anything else is
// refused here, and every address libhdf5 would follow from an object header is checked to land where it must.

#include <string>
#include <string_view>

namespace flexbody::format::detail {

/// Checks the HDF5 part of a sealed body file (`bytes` is the whole file; the superblock sits at `base`, after the
/// seal): the superblock, then every object header reachable through hard links from the root group, and their
/// continuation chunks. Returns "" if the structure is the subset fbprep writes, else what is wrong, e.g. "the
/// object header at 1252 stores its attributes densely (a fractal heap at 2400)".
[[nodiscard]] std::string check_hdf5_structure(std::string_view bytes, std::size_t base);

}  // namespace flexbody::format::detail
