#pragma once
// blas_gemm.hpp (internal): dense matrix products on the BLAS. Eigen's own kernels are compiled for the baseline
// x86-64 (SSE2; see the top CMakeLists.txt on -march), while the BLAS Debian loads at run time (OpenBLAS through the
// libblas.so.3 alternative) picks AVX-512 kernels on this machine and runs on all cores. Used for the tall, thin
// products of the eigen stage and the GCMS constants.

#include <Eigen/Core>

namespace flexbody::preprocess::blas {

enum class Op { none, transpose };

/// C = alpha op(A) op(B) + beta C for column-major A, B, C with leading dimensions lda, ldb, ldc; op(A) is m x k,
/// op(B) k x n. Throws std::invalid_argument if a dimension exceeds the BLAS's 32-bit integers.
void gemm(Op op_a, Op op_b, Eigen::Index m, Eigen::Index n, Eigen::Index k, double alpha, const double* a,
          Eigen::Index lda, const double* b, Eigen::Index ldb, double beta, double* c, Eigen::Index ldc);

/// Aᵀ B for A (n x k) and B (n x m): the Gram-type products of long fields.
[[nodiscard]] Eigen::MatrixXd transposed_product(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b);

}  // namespace flexbody::preprocess::blas
