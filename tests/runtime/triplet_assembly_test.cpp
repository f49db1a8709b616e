// The repeated-pattern sparse assembly of the runtime (runtime/src/kernels/triplet_assembly.hpp) against
// setFromTriplets: the same (row, column) sequence with new values, duplicates summed, a changed sequence, and a
// matrix that is not the one it built last.
#include "kernels/triplet_assembly.hpp"

#include <Eigen/SparseCore>
#include <gtest/gtest.h>

#include <vector>

namespace {

using Entries = std::vector<Eigen::Triplet<double>>;

Eigen::MatrixXd reference(Eigen::Index rows, Eigen::Index cols, const Entries& entries) {
  Eigen::SparseMatrix<double> m(rows, cols);
  m.setFromTriplets(entries.begin(), entries.end());
  return Eigen::MatrixXd(m);
}

TEST(TripletAssembly, RebuildsAlongTheRecordOrAfresh) {
  flexbody::runtime::detail::TripletAssembly assembly;
  Entries entries = {{0, 0, 1.0}, {2, 1, 2.0}, {0, 0, 3.0}, {1, 2, 0.0}, {2, 2, -1.0}};  // (0, 0) twice, one zero
  Eigen::SparseMatrix<double> m;
  assembly.assemble(3, 3, entries, m);
  EXPECT_EQ(Eigen::MatrixXd(m), reference(3, 3, entries));
  EXPECT_EQ(m.nonZeros(), 4);  // the explicit zero is kept: the pattern holds every entry's place
  for (int k = 0; k < 5; ++k) entries[static_cast<std::size_t>(k)] = {entries[static_cast<std::size_t>(k)].row(),
                                                                        entries[static_cast<std::size_t>(k)].col(), 10.0 + k};
  const double* storage = m.valuePtr();
  assembly.assemble(3, 3, entries, m);  // the same sequence: values only, in place
  EXPECT_EQ(m.valuePtr(), storage);
  EXPECT_EQ(Eigen::MatrixXd(m), reference(3, 3, entries));
  entries.emplace_back(1, 0, 5.0);  // a new entry: built afresh
  assembly.assemble(3, 3, entries, m);
  EXPECT_EQ(Eigen::MatrixXd(m), reference(3, 3, entries));
  Eigen::SparseMatrix<double> other(3, 3);  // a matrix it did not build: afresh
  other.insert(1, 1) = 7.0;
  other.makeCompressed();
  assembly.assemble(3, 3, entries, other);
  EXPECT_EQ(Eigen::MatrixXd(other), reference(3, 3, entries));
  Eigen::SparseMatrix<double> copy = m;  // the same pattern in another object: the record applies
  entries.back() = {1, 0, -5.0};
  assembly.assemble(3, 3, entries, copy);
  EXPECT_EQ(Eigen::MatrixXd(copy), reference(3, 3, entries));
}

}  // namespace
