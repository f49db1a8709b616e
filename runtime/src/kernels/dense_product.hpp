#pragma once
// dense_product.hpp (internal): y = A x for the runtime's per-iteration dense matrices, K̂ ξ̄ (Eq. 87) and
// C⁻¹ r (formulations.md, "The Method": the constant core), both 3 n_f square, and the small products of the Newton
// solve.
//
// Eigen picks its vector width when it is compiled: a portable build (no -march) runs these products with SSE2,
// two doubles per instruction. This kernel is compiled for several instruction sets and the dynamic loader picks
// the widest the machine has (GCC's target_clones), so a distribution build gets AVX2 or AVX-512 where they exist.
// It is fastest on a PaddedMatrix, whose columns start on 64-byte boundaries: at 180 square, 2.6-3.4 µs against
// 3.4-5.1 µs for the same product on columns that straddle cache lines (bench/README.md, "runtime_bench").

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <unordered_map>

namespace flexbody::runtime::detail {

/// y = A x. x and y hold a.cols() and a.rows() doubles and must not overlap each other or A.
void dense_product(const Eigen::MatrixXd& a, const double* x, double* y);

/// An immutable dense matrix stored for dense_product: column-major, each column starting on a 64-byte boundary
/// (the leading dimension rounded up to 8 doubles). Copies share the storage.
class PaddedMatrix {
 public:
  PaddedMatrix() = default;
  explicit PaddedMatrix(const Eigen::Ref<const Eigen::MatrixXd>& a);
  // Copies only (they share the storage): a move would leave an object with sizes and no storage.
  PaddedMatrix(const PaddedMatrix&) = default;
  PaddedMatrix& operator=(const PaddedMatrix&) = default;
  [[nodiscard]] Eigen::Index rows() const { return rows_; }
  [[nodiscard]] Eigen::Index cols() const { return cols_; }
  /// y = A x, as dense_product.
  void multiply(const double* x, double* y) const;
  /// The storage, shared by copies (for tests).
  [[nodiscard]] const double* storage() const { return data_.get(); }
  /// Whether this holds exactly `a` (same sizes, bitwise-equal entries).
  [[nodiscard]] bool holds(const Eigen::Ref<const Eigen::MatrixXd>& a) const;

 private:
  Eigen::Index rows_ = 0, cols_ = 0, stride_ = 0;
  std::shared_ptr<const double[]> data_;
};

/// Constant matrices stored once when they are equal: the bodies of a scene made of N copies of one part multiply by
/// one K̂ and one C⁻¹, which then stay in cache. A chain of 64 brackets streamed 64 copies of each (23 KB at 18
/// fields) from memory at every iteration, and its cost per body per step was twice a single bracket's.
class SharedMatrices {
 public:
  /// A PaddedMatrix holding `a`: one made earlier from a bitwise-equal matrix (sharing its storage), or a new one.
  [[nodiscard]] PaddedMatrix get(const Eigen::Ref<const Eigen::MatrixXd>& a);

 private:
  std::unordered_multimap<std::size_t, PaddedMatrix> made_;  ///< by a hash of the entries' bytes
};

}  // namespace flexbody::runtime::detail
