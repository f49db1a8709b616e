#include "blas_gemm.hpp"

#include <cblas.h>

#include <limits>
#include <stdexcept>

namespace flexbody::preprocess::blas {
namespace {

int blas_int(Eigen::Index value) {
  if (value > std::numeric_limits<int>::max())
    throw std::invalid_argument("BLAS: a dimension exceeds the BLAS's 32-bit integers");
  return static_cast<int>(value);
}

CBLAS_TRANSPOSE cblas_op(Op op) { return op == Op::transpose ? CblasTrans : CblasNoTrans; }

}  // namespace

void gemm(Op op_a, Op op_b, Eigen::Index m, Eigen::Index n, Eigen::Index k, double alpha, const double* a,
          Eigen::Index lda, const double* b, Eigen::Index ldb, double beta, double* c, Eigen::Index ldc) {
  cblas_dgemm(CblasColMajor, cblas_op(op_a), cblas_op(op_b), blas_int(m), blas_int(n), blas_int(k), alpha, a,
              blas_int(lda), b, blas_int(ldb), beta, c, blas_int(ldc));
}

Eigen::MatrixXd transposed_product(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  if (a.rows() != b.rows()) throw std::logic_error("transposed_product: A and B differ in their number of rows");
  Eigen::MatrixXd c(a.cols(), b.cols());
  if (c.size() == 0) return c;
  if (a.rows() == 0) return c.setZero();
  gemm(Op::transpose, Op::none, a.cols(), b.cols(), a.rows(), 1.0, a.data(), a.rows(), b.data(), b.rows(), 0.0,
       c.data(), c.rows());
  return c;
}

}  // namespace flexbody::preprocess::blas
