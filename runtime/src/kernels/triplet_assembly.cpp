#include "triplet_assembly.hpp"

#include <algorithm>

namespace flexbody::runtime::detail {

void TripletAssembly::assemble(Eigen::Index rows, Eigen::Index cols, const std::vector<Eigen::Triplet<double>>& entries,
                               Eigen::SparseMatrix<double>& matrix) {
  const std::size_t count = entries.size();
  bool same = matrix.rows() == rows && matrix.cols() == cols && matrix.isCompressed() && rows_.size() == count &&
              outer_.size() == static_cast<std::size_t>(cols) + 1 &&
              std::equal(outer_.begin(), outer_.end(), matrix.outerIndexPtr()) &&
              static_cast<std::size_t>(matrix.nonZeros()) == inner_.size() &&
              std::equal(inner_.begin(), inner_.end(), matrix.innerIndexPtr());
  for (std::size_t k = 0; same && k < count; ++k) same = entries[k].row() == rows_[k] && entries[k].col() == columns_[k];
  if (same) {
    double* values = matrix.valuePtr();
    std::fill(values, values + matrix.nonZeros(), 0.0);
    for (std::size_t k = 0; k < count; ++k) values[places_[k]] += entries[k].value();
    return;
  }
  matrix.resize(rows, cols);
  matrix.setFromTriplets(entries.begin(), entries.end());  // sums duplicates; sorted rows in each column
  matrix.makeCompressed();
  rows_.resize(count);
  columns_.resize(count);
  places_.resize(count);
  const int* outer = matrix.outerIndexPtr();
  const int* inner = matrix.innerIndexPtr();
  for (std::size_t k = 0; k < count; ++k) {
    rows_[k] = static_cast<int>(entries[k].row());
    columns_[k] = static_cast<int>(entries[k].col());
    const int* first = inner + outer[columns_[k]];
    places_[k] = static_cast<int>(std::lower_bound(first, inner + outer[columns_[k] + 1], rows_[k]) - inner);
  }
  outer_.assign(outer, outer + cols + 1);
  inner_.assign(inner, inner + matrix.nonZeros());
}

}  // namespace flexbody::runtime::detail
