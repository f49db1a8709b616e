#include "block_lanczos.hpp"

#include "../linalg/blas_gemm.hpp"
#include "lanczos_basis_limit.hpp"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

namespace flexbody::preprocess {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;

// The basis V (n x k) is read in every step; its products with thin blocks run on the BLAS (linalg/blas_gemm.hpp).
using detail::kMaxLanczosBasisBytes;

// C = Aᵀ B for column-major A (n x k) and B (n x m) with leading dimension n; C is k x m.
MatrixXd transposed_product(const double* a, Index k, const double* b, Index m, Index n) {
  MatrixXd c(k, m);
  blas::gemm(blas::Op::transpose, blas::Op::none, k, m, n, 1.0, a, n, b, n, 0.0, c.data(), k);
  return c;
}

// B <- alpha A C + beta B for column-major A (n x k, leading dimension n), C (k x m) and B (n x m, leading dimension n).
void add_product(double alpha, const double* a, Index k, const MatrixXd& c, double* b, Index n, double beta = 1.0) {
  blas::gemm(blas::Op::none, blas::Op::none, n, c.cols(), k, alpha, a, n, c.data(), k, beta, b, n);
}

// Y = M̄ X = (M_s ⊗ I3) X for a block of node-interleaved columns, from M_s with both triangles: node rows on all
// threads, each node's entries read once for every column of the block. A column at a time on the upper triangle
// (apply_vector_mass, one thread per column) took 3.3 s of 1.05M DOFs' eigen stage.
void apply_mass(const SparseMatrix& mass_full, const double* x, double* y, Index columns) {
  const Index nodes = mass_full.cols(), n = 3 * nodes;
  const std::int64_t* start = mass_full.outerIndexPtr();
  const std::int64_t* row = mass_full.innerIndexPtr();
  const double* value = mass_full.valuePtr();
#pragma omp parallel for schedule(static)
  for (Index node = 0; node < nodes; ++node)
    for (Index c = 0; c < columns; ++c) {
      const double* xc = x + c * n;
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      for (std::int64_t p = start[node]; p < start[node + 1]; ++p) {
        const double m = value[p];
        const double* xi = xc + 3 * row[p];
        s0 += m * xi[0], s1 += m * xi[1], s2 += m * xi[2];
      }
      double* yc = y + c * n + 3 * node;
      yc[0] = s0, yc[1] = s1, yc[2] = s2;
    }
}

// Writes zeros into a block of the basis on all threads before its first use: the page faults of fresh memory
// (the kernel zeroes each page) then run on both cores instead of inside the one-thread copy of a solve's result.
void first_touch(double* x, Index size) {
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < size; ++i) x[i] = 0.0;
}

// A block of the basis and its M̄ image, both n x b, column-major with leading dimension n.
struct Block {
  double* w;
  double* mw;
  Index n, b;
};

// Removes from W its M̄-components along k basis vectors V (classical Gram-Schmidt in BLAS 3): C = Vᵀ M̄ W,
// W -= V C and, where M̄ V is at hand, M̄ W -= (M̄ V) C. Without it (mv = nullptr) the caller recomputes M̄ W.
// Returns C (k x b).
MatrixXd project_out(const double* v, const double* mv, Index k, const Block& block) {
  MatrixXd c = transposed_product(v, k, block.mw, block.b, block.n);
  add_product(-1.0, v, k, c, block.w, block.n);
  if (mv != nullptr) add_product(-1.0, mv, k, c, block.mw, block.n);
  return c;
}

Eigen::VectorXd mass_norms(const Block& block) {
  Eigen::Map<const MatrixXd> w(block.w, block.n, block.b), mw(block.mw, block.n, block.b);
  return w.cwiseProduct(mw).colwise().sum().transpose().cwiseMax(0.0).cwiseSqrt();
}

// Makes W's columns M̄-orthonormal by SVQB (Stathopoulos & Wu 2002), twice: G = Wᵀ M̄ W scaled to a unit diagonal,
// G = U S Uᵀ, W <- W D U S^-1/2. Returns R with W_before = W_after R. Throws if the columns are dependent (the
// Krylov space is exhausted: an invariant subspace of OP has been found).
MatrixXd orthonormalize(const Block& block, Index basis_size, MatrixXd& scratch) {
  MatrixXd r = MatrixXd::Identity(block.b, block.b);
  for (int pass = 0; pass < 2; ++pass) {
    MatrixXd g = transposed_product(block.w, block.b, block.mw, block.b, block.n);
    g = 0.5 * (g + g.transpose()).eval();
    const Eigen::VectorXd diagonal = g.diagonal();
    if (!(diagonal.minCoeff() > 0.0))
      throw std::runtime_error(fmt::format("block Lanczos: the Krylov space is exhausted after {} vectors "
                                           "(use --eigensolver arpack)", basis_size));
    const Eigen::VectorXd scale = diagonal.cwiseSqrt().cwiseInverse();
    const Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(scale.asDiagonal() * g * scale.asDiagonal());
    const Eigen::VectorXd s = eigen.eigenvalues();
    // Columns dependent to within round-off of the Gram matrix: no new direction left.
    if (!(s.minCoeff() > 1e3 * std::numeric_limits<double>::epsilon() * static_cast<double>(block.b) * s.maxCoeff()))
      throw std::runtime_error(fmt::format("block Lanczos: the Krylov space is exhausted after {} vectors "
                                           "(use --eigensolver arpack)", basis_size));
    const MatrixXd q = scale.asDiagonal() * eigen.eigenvectors() * s.cwiseSqrt().cwiseInverse().asDiagonal();
    for (double* x : {block.w, block.mw}) {  // X <- X Q through the scratch block (no n x b allocation per call)
      add_product(1.0, x, block.b, q, scratch.data(), block.n, 0.0);
      std::copy_n(scratch.data(), block.n * block.b, x);
    }
    // W_before = W_after Q^-1, with Q^-1 = S^1/2 Uᵀ D^-1.
    r = (s.cwiseSqrt().asDiagonal() * eigen.eigenvectors().transpose() * scale.cwiseInverse().asDiagonal() * r).eval();
  }
  return r;
}

}  // namespace

Index block_lanczos_basis_limit(int nev, Index block, Index n) {
  const Index wanted = std::max<Index>(20 * static_cast<Index>(nev), 8 * block);
  const auto affordable = static_cast<Index>(kMaxLanczosBasisBytes / (8.0 * static_cast<double>(n)));
  const Index limit = std::min({wanted + block - 1, affordable, n - 6});
  return limit / block * block;
}

EigenPairs solve_block_lanczos(ShiftSolve& op, const VectorMassOperator& mass, int nev,
                               const EigensolverOptions& options) {
  const Index n = op.rows();
  const Index b = options.block_size;
  if (b < 1) throw std::invalid_argument(fmt::format("block Lanczos: the block size must be >= 1, got {}", b));
  const Index k_max = block_lanczos_basis_limit(nev, b, n);
  if (k_max < nev + b)
    throw std::invalid_argument(fmt::format("block Lanczos: {} modes in blocks of {} need more than the {} basis "
                                            "vectors this mesh allows (use --eigensolver arpack)", nev, b, k_max));
  // 1e-2 x ARPACK's tolerance, as for slepc: a block Krylov space of the same size holds lower powers of OP, so
  // at the same Ritz estimate its vectors keep more of the stiff end of the spectrum. On the bracket at 43k DOFs
  // (26 modes, b = 8) tol = 1e-12 left the worst residual at 393x its rounding floor, 1e-14 at 6x for 16 more
  // vectors (ARPACK's: 1.05x).
  const double tolerance = 1e-2 * (options.tolerance > 0.0 ? options.tolerance : std::numeric_limits<double>::epsilon());

  // The basis V (only the columns in use are ever touched) and the M̄ images of its two newest blocks and of the
  // block being built. M̄ V as a whole is not kept: at 1.05M DOFs it was 1.4 GB more memory whose first touch (page
  // faults) and updates cost more than the one M̄ product per block that recomputes M̄ W after the full pass.
  MatrixXd v(n, k_max), mv_previous(n, b), mv_newest(n, b), mw(n, b);
  const SparseMatrix mass_full = full_from_upper(mass.scalar_mass_upper());
  MatrixXd h;  // OP V_j = sum_i V_i H_ij: block tridiagonal up to round-off; grown as the basis grows
  auto reserve = [&](Index size) {  // h at least size x size, doubling (k_max^2 would be 0.6 GB for 500 modes)
    if (size <= h.rows()) return;
    const Index grown = std::min(k_max, std::max(size, 2 * h.rows()));
    h.conservativeResizeLike(MatrixXd::Zero(grown, grown));
  };
  MatrixXd scratch(n, b);
  EigenPairs result;
  {  // V_0 = P (K̄ - sigma M̄)^-1 M̄ X for a reproducible random X: inside the range of the deflated operator
    std::mt19937_64 generator(20230131);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    MatrixXd x(n, b), mx(n, b);
    for (Index i = 0; i < x.size(); ++i) x.data()[i] = uniform(generator);
    apply_mass(mass_full, x.data(), mx.data(), b);
    op.perform_block(mx.data(), v.data(), b);
    result.operator_applies += static_cast<int>(b);
    apply_mass(mass_full, v.data(), mv_newest.data(), b);
    (void)orthonormalize(Block{v.data(), mv_newest.data(), n, b}, b, scratch);
  }
  const double reorthogonalize = std::sqrt(std::numeric_limits<double>::epsilon());
  // A new column whose M̄-norm the projections reduce below this fraction is round-off, not a new direction.
  const double exhausted = 1e3 * std::numeric_limits<double>::epsilon();
  Index last_check = 0;  // basis size at the last Rayleigh-Ritz step
  for (Index k = b;; k += b) {  // k: basis vectors so far; the newest block starts at j = k - b
    const Index j = k - b;
    if (k + b > k_max)
      throw std::runtime_error(fmt::format("block Lanczos: {} modes not converged within {} basis vectors (use "
                                           "--eigensolver arpack)", nev, k_max));
    const Block next{v.col(k).data(), mw.data(), n, b};
    first_touch(next.w, n * b);
    op.perform_block(mv_newest.data(), next.w, b);  // W = OP V_j = P (K̄ - sigma M̄)^-1 (M̄ V_j)
    result.operator_applies += static_cast<int>(b);
    apply_mass(mass_full, next.w, next.mw, b);
    reserve(k + b);
    const Eigen::VectorXd before = mass_norms(next);
    // Gram-Schmidt: the two newest blocks first (the large components), then the whole basis, which also restores
    // the orthogonality that Lanczos loses as Ritz values converge; once more if that pass still removed much.
    if (j > 0) h.block(j - b, j, b, b) += project_out(v.col(j - b).data(), mv_previous.data(), b, next);
    h.block(j, j, b, b) += project_out(v.col(j).data(), mv_newest.data(), b, next);
    for (int pass = 0; pass < 2; ++pass) {
      const MatrixXd c = project_out(v.data(), nullptr, k, next);
      apply_mass(mass_full, next.w, next.mw, b);
      h.block(0, j, k, b) += c;
      const Eigen::VectorXd left = mass_norms(next);
      bool again = false;
      for (Index col = 0; col < b; ++col) again |= c.col(col).norm() > reorthogonalize * left(col);
      if (!again) break;
    }
    const Eigen::VectorXd after = mass_norms(next);
    for (Index col = 0; col < b; ++col)
      if (!(after(col) > exhausted * before(col)))
        throw std::runtime_error(fmt::format("block Lanczos: the Krylov space is exhausted after {} vectors (use "
                                             "--eigensolver arpack)", k));
    h.block(k, j, b, b) = orthonormalize(next, k + b, scratch);
    ++result.iterations;
    std::swap(mv_previous, mv_newest);  // O(1): Eigen swaps the buffers
    std::swap(mv_newest, mw);

    // Rayleigh-Ritz on T = Vᵀ M̄ OP V (k x k); the residual of a Ritz pair (theta, V s) is V_next H_next s_last,
    // whose M̄-norm is ||H_next s_last|| (s_last: s's entries of the newest block).
    // Up to 400 vectors every step (an eigensolve of T takes milliseconds there); beyond, once the basis has grown by
    // 5 %, so that the eigensolves of T cost a bounded multiple of the last one.
    if (k < nev || (k > 400 && 20 * (k - last_check) < k)) continue;
    last_check = k;
    const MatrixXd t = 0.5 * (h.topLeftCorner(k, k) + h.topLeftCorner(k, k).transpose());
    const Eigen::SelfAdjointEigenSolver<MatrixXd> ritz(t);
    const MatrixXd residuals = h.block(k, j, b, b) * ritz.eigenvectors().bottomRows(b);
    bool converged = true;
    for (Index i = k - nev; i < k; ++i)  // the nev largest theta, ascending
      converged &= residuals.col(i).norm() <= tolerance * std::abs(ritz.eigenvalues()(i));
    if (!converged) continue;

    // lambda = sigma + 1 / theta, ascending as theta descends; vectors V S.
    const MatrixXd s = ritz.eigenvectors().rightCols(nev).rowwise().reverse();
    result.eigenvalues = ritz.eigenvalues().tail(nev).reverse().cwiseInverse().array() + op.shift();
    result.vectors = MatrixXd::Zero(n, nev);
    add_product(1.0, v.data(), k, s, result.vectors.data(), n);
    return result;
  }
}

}  // namespace flexbody::preprocess
