#include "flexbody/preprocess/gcms_matrices.hpp"

#include "../linalg/blas_gemm.hpp"

#include <algorithm>
#include <stdexcept>

namespace flexbody::preprocess {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Fields per pass of reduced_stiffness: bounds the work array to 3 n_n x 3 kFieldChunk doubles.
constexpr Eigen::Index kFieldChunk = 16;

// Z = K̄ (U ⊗ I3) for the fields U (n_n x b, row-major), as a 3 n_n x 3b row-major array whose column
// k b + f belongs to component k of field f (component-major, so the inner loop over f is contiguous).
// `stiffness_full` holds both triangles: its column c is row c, so each DOF row of Z is a gather over
// one column, and the rows are computed in parallel without sharing a write.
RowMatrix stiffness_times_fields(const SparseMatrix& stiffness_full, const RowMatrix& u) {
  const Eigen::Index b = u.cols(), n = stiffness_full.cols();
  // Not RowMatrix::Zero: GCC turns an allocation and a zero fill into calloc, whose fresh pages the loop below would
  // first read (+=) and then write, a copy-on-write fault per page with a TLB shootdown across the threads; on two
  // threads that made this loop twice as slow as on one (1.6 s against 0.75 s at 219k DOFs, perf: do_wp_page and
  // flush_tlb IPIs). Each thread zeroes its own rows first.
  RowMatrix z(n, 3 * b);
  const std::int64_t* start = stiffness_full.outerIndexPtr();
  const std::int64_t* rows = stiffness_full.innerIndexPtr();
  const double* values = stiffness_full.valuePtr();
#pragma omp parallel for schedule(static)
  for (Eigen::Index c = 0; c < n; ++c) {
    double* out = z.row(c).data();
    std::fill_n(out, 3 * b, 0.0);
    for (std::int64_t p = start[c]; p < start[c + 1]; ++p) {
      const Eigen::Index r = rows[p];
      const double k = values[p];
      // (U ⊗ I3) has U(node, f) at row 3 node + comp, column (comp, f).
      double* target = out + (r % 3) * b;
      const double* source = u.row(r / 3).data();
      for (Eigen::Index f = 0; f < b; ++f) target[f] += k * source[f];
    }
  }
  return z;
}

}  // namespace

Eigen::MatrixXd generalized_field_matrix(const RowMatrixX3d& nodes, const Eigen::MatrixXd& fields) {
  Eigen::MatrixXd y(nodes.rows(), 4 + fields.cols());
  y.col(0).setOnes();
  y.middleCols(1, 3) = nodes;
  y.rightCols(fields.cols()) = fields;
  return y;
}

Eigen::MatrixXd gcms_mass_matrix(const SparseMatrix& scalar_mass_upper, const RowMatrixX3d& nodes,
                                 const Eigen::MatrixXd& fields) {
  return gcms_mass_matrix(scalar_mass_upper, nodes, fields, scalar_mass_upper.selfadjointView<Eigen::Upper>() * fields);
}

Eigen::MatrixXd gcms_mass_matrix(const SparseMatrix& scalar_mass_upper, const RowMatrixX3d& nodes,
                                 const Eigen::MatrixXd& fields, const Eigen::MatrixXd& mass_fields) {
  const Eigen::Index n_f = fields.cols();
  if (nodes.rows() != scalar_mass_upper.rows() || fields.rows() != nodes.rows() || mass_fields.rows() != nodes.rows() ||
      mass_fields.cols() != n_f)
    throw std::logic_error("gcms_mass_matrix: nodes, fields and M_s disagree on n_n");
  const Eigen::MatrixXd rigid = generalized_field_matrix(nodes, Eigen::MatrixXd(nodes.rows(), 0));  // [1, X̄]
  const Eigen::MatrixXd mass_rigid = scalar_mass_upper.selfadjointView<Eigen::Upper>() * rigid;
  Eigen::MatrixXd g(4 + n_f, 4 + n_f);
  g.topLeftCorner<4, 4>() = rigid.transpose() * mass_rigid;
  g.topRightCorner(4, n_f) = rigid.transpose() * mass_fields;
  g.bottomLeftCorner(n_f, 4) = g.topRightCorner(4, n_f).transpose();
  g.bottomRightCorner(n_f, n_f) = blas::transposed_product(fields, mass_fields);
  return 0.5 * (g + g.transpose());  // symmetric to the last bit
}

Eigen::MatrixXd reduced_stiffness(const SparseMatrix& stiffness_upper, const Eigen::MatrixXd& fields) {
  const Eigen::Index n_n = fields.rows(), n_f = fields.cols();
  if (stiffness_upper.rows() != 3 * n_n) throw std::logic_error("reduced_stiffness: K̄ must be 3 n_n square");
  const SparseMatrix stiffness_full = full_from_upper(stiffness_upper);
  Eigen::MatrixXd k_hat(3 * n_f, 3 * n_f);
  for (Eigen::Index f0 = 0; f0 < n_f; f0 += kFieldChunk) {
    const Eigen::Index b = std::min(kFieldChunk, n_f - f0);
    const RowMatrix chunk = fields.middleCols(f0, b);
    const RowMatrix z = stiffness_times_fields(stiffness_full, chunk);
    // Row i of zn holds rows 3i, 3i+1, 3i+2 of z, so that
    // K̂[3g + l, 3(f0 + f) + k] = sum_i U(i, g) z(3i + l, k b + f) = w(g, l 3b + k b + f).
    // Only the rows g < f0 + b: K̂ is symmetric, the rest is the transpose of later chunks' rows.
    const Eigen::Index g_end = f0 + b;
    // w = Uᵀ zn on the BLAS (2.4e10 flops in all at 1M DOFs and 78 fields: 2 s in Eigen's SSE2 kernels); zn is
    // row-major n_n x 9b, i.e. column-major 9b x n_n, hence the second transpose.
    Eigen::MatrixXd w(g_end, 9 * b);
    blas::gemm(blas::Op::transpose, blas::Op::transpose, g_end, 9 * b, n_n, 1.0, fields.data(), n_n, z.data(), 9 * b,
               0.0, w.data(), g_end);
    for (Eigen::Index g = 0; g < g_end; ++g)
      for (int l = 0; l < 3; ++l)
        for (int k = 0; k < 3; ++k)
          for (Eigen::Index f = 0; f < b; ++f) k_hat(3 * g + l, 3 * (f0 + f) + k) = w(g, l * 3 * b + k * b + f);
  }
  // Lower block triangle from the upper one, then the average with the transpose makes the diagonal
  // blocks symmetric to the last bit.
  for (Eigen::Index f = 0; f < n_f; ++f)
    for (Eigen::Index g = f + 1; g < n_f; ++g) k_hat.block<3, 3>(3 * g, 3 * f) = k_hat.block<3, 3>(3 * f, 3 * g).transpose();
  return 0.5 * (k_hat + k_hat.transpose());
}

}  // namespace flexbody::preprocess
