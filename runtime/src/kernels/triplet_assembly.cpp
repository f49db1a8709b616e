#include "triplet_assembly.hpp"

#include <algorithm>
#include <cstdint>

namespace flexbody::runtime::detail {

namespace {

std::uint64_t key(const Eigen::Triplet<double>& e) {
  return static_cast<std::uint64_t>(static_cast<std::uint32_t>(e.row())) << 32U | static_cast<std::uint32_t>(e.col());
}

}  // namespace

void TripletAssembly::assemble(Eigen::Index rows, Eigen::Index cols, const std::vector<Eigen::Triplet<double>>& entries,
                               Eigen::SparseMatrix<double>& matrix) {
  const std::size_t count = entries.size();
  const bool same_pattern = matrix.rows() == rows && matrix.cols() == cols && matrix.isCompressed() &&
                            keys_.size() == count && outer_.size() == static_cast<std::size_t>(cols) + 1 &&
                            std::equal(outer_.begin(), outer_.end(), matrix.outerIndexPtr()) &&
                            static_cast<std::size_t>(matrix.nonZeros()) == inner_.size() &&
                            std::equal(inner_.begin(), inner_.end(), matrix.innerIndexPtr());
  if (same_pattern) {  // one pass: each entry checked against the record and added; a mismatch rebuilds below
    double* values = matrix.valuePtr();
    std::fill(values, values + matrix.nonZeros(), 0.0);
    std::size_t k = 0;
    for (; k < count && key(entries[k]) == keys_[k]; ++k) values[places_[k]] += entries[k].value();
    if (k == count) return;
  }
  matrix.resize(rows, cols);
  matrix.setFromTriplets(entries.begin(), entries.end());  // sums duplicates; sorted rows in each column
  matrix.makeCompressed();
  keys_.resize(count);
  places_.resize(count);
  const int* outer = matrix.outerIndexPtr();
  const int* inner = matrix.innerIndexPtr();
  for (std::size_t k = 0; k < count; ++k) {
    keys_[k] = key(entries[k]);
    const auto row = static_cast<int>(entries[k].row());
    const int* first = inner + outer[entries[k].col()];
    places_[k] = static_cast<int>(std::lower_bound(first, inner + outer[entries[k].col() + 1], row) - inner);
  }
  outer_.assign(outer, outer + cols + 1);
  inner_.assign(inner, inner + matrix.nonZeros());
}

}  // namespace flexbody::runtime::detail
