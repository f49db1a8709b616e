#pragma once
// triplet_assembly.hpp (internal): a sparse matrix summed from triplets whose (row, column) sequence repeats from one
// build to the next, as the blocks of a constraint Jacobian or of a reduced Newton matrix come in the same order at
// every build. The first build sorts them (setFromTriplets) and records where each lands; later builds only add the
// values along that record. The sort and transposition took most of a 64-link rigid chain's matrix build outside
// KLU, and 2 of the 4 ms of a 1024-link chain's Jacobian.

#include <Eigen/SparseCore>

#include <cstdint>
#include <vector>

namespace flexbody::runtime::detail {

class TripletAssembly {
 public:
  /// `matrix` (rows x cols, compressed) = the sums of `entries`. The fast path needs `matrix` to be the one this
  /// object built last, unchanged: that is checked (its pattern is compared), and any other matrix is built afresh.
  void assemble(Eigen::Index rows, Eigen::Index cols, const std::vector<Eigen::Triplet<double>>& entries,
                Eigen::SparseMatrix<double>& matrix);

 private:
  std::vector<std::uint64_t> keys_;  ///< the last entries' (row, column), packed
  std::vector<int> places_;          ///< and each one's index in the values
  std::vector<int> outer_, inner_;            ///< the pattern built last
};

}  // namespace flexbody::runtime::detail
