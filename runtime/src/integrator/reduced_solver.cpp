#include "reduced_solver.hpp"

#include <klu.h>

#include <Eigen/LU>

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace flexbody::runtime::detail {
namespace {

// A refactorization keeps the pivot sequence of the last pivoting factorization. Its pivots have degraded when
// KLU's pivot ratio min |u_ii| / max |u_ii| falls this far below what the pivoting factorization reached; then
// the matrix is factorized afresh with partial pivoting (KLU's default threshold, 0.001).
constexpr double kPivotDegradation = 1e-3;

}  // namespace

void DenseReducedSolver::factor(Eigen::Index size, const std::vector<Eigen::Triplet<double>>& entries) {
  matrix_.resize(size, size);  // its size only: a one-body step is a few µs, the sparse copy cost 0.1 µs of it
  dense_.setZero(size, size);
  for (const Eigen::Triplet<double>& e : entries) dense_(e.row(), e.col()) += e.value();
  // The inverse explicitly: a solve is then one product with the dense kernel, where Eigen's blocked triangular
  // solves took 0.4 µs each at 21 rows (7 % of a 20-mode step, two per iteration). The matrix is a saddle point
  // whose condition estimate is about 1e9 in the bracket pendulum (where the product agreed with LU solves to
  // 5e-12) and passes 1e14 in the driven spin-up test, which converges as it did with LU solves: a Newton matrix
  // needs to be only roughly right, the residual is exact. An exactly zero pivot gives non-finite entries, which
  // the integrator reports as a singular Newton matrix; a matrix singular only after rounding gives large
  // corrections, as an LU solve would, and the iteration's failure to converge is reported.
  inverse_ = PaddedMatrix(Eigen::PartialPivLU<Eigen::MatrixXd>(dense_).inverse());
}

void DenseReducedSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  x.resize(b.size());
  inverse_.multiply(b.data(), x.data());
}

struct SparseReducedSolver::Klu {
  klu_common common{};
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  void free_numeric() {
    if (numeric) klu_free_numeric(&numeric, &common);
  }
  void free_all() {
    free_numeric();
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
};

SparseReducedSolver::SparseReducedSolver() : klu_(std::make_unique<Klu>()) {
  klu_defaults(&klu_->common);
  klu_->common.halt_if_singular = 1;  // a singular matrix: no factor (solve() then gives NaN)
}

SparseReducedSolver::~SparseReducedSolver() { klu_->free_all(); }

void SparseReducedSolver::factor(Eigen::Index size, const std::vector<Eigen::Triplet<double>>& entries) {
  if (size > std::numeric_limits<int>::max() / 2)
    throw std::runtime_error("the reduced Newton matrix has more rows than KLU's 32-bit indices take");
  matrix_.resize(size, size);
  matrix_.setFromTriplets(entries.begin(), entries.end());  // sums duplicates, keeps explicit zeros: the scene's pattern
  matrix_.makeCompressed();
  const int n = static_cast<int>(size);
  int* outer = matrix_.outerIndexPtr();
  int* inner = matrix_.innerIndexPtr();
  double* values = matrix_.valuePtr();
  const auto nonzeros = static_cast<std::size_t>(matrix_.nonZeros());
  const bool same_pattern = klu_->symbolic && outer_.size() == static_cast<std::size_t>(n + 1) &&
                            std::equal(outer_.begin(), outer_.end(), outer) && inner_.size() == nonzeros &&
                            std::equal(inner_.begin(), inner_.end(), inner);
  if (!same_pattern) {  // the ordering, once per pattern
    klu_->free_all();
    outer_.assign(outer, outer + n + 1);
    inner_.assign(inner, inner + nonzeros);
    klu_->symbolic = klu_analyze(n, outer, inner, &klu_->common);
    ++analyses_;
    if (!klu_->symbolic) throw std::runtime_error("KLU could not analyse the reduced Newton matrix (status " +
                                                  std::to_string(klu_->common.status) + ")");
  }
  singular_ = true;
  if (klu_->numeric && klu_refactor(outer, inner, values, klu_->symbolic, klu_->numeric, &klu_->common) &&
      klu_rcond(klu_->symbolic, klu_->numeric, &klu_->common) && klu_->common.rcond >= kPivotDegradation * fresh_rcond_) {
    singular_ = false;
    return;
  }
  klu_->free_numeric();
  klu_->numeric = klu_factor(outer, inner, values, klu_->symbolic, &klu_->common);
  ++pivoting_;
  if (!klu_->numeric) {  // singular: solve() reports it as non-finite, and the integrator names it
    if (klu_->common.status == KLU_SINGULAR) return;
    throw std::runtime_error("KLU could not factorize the reduced Newton matrix (" + std::to_string(size) +
                             " rows): status " + std::to_string(klu_->common.status) +
                             (klu_->common.status == KLU_OUT_OF_MEMORY ? " (out of memory)" : ""));
  }
  klu_rcond(klu_->symbolic, klu_->numeric, &klu_->common);
  fresh_rcond_ = klu_->common.rcond;
  singular_ = !(fresh_rcond_ > 0.0);
}

void SparseReducedSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  x = b;
  if (singular_) {
    x.setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  klu_solve(klu_->symbolic, klu_->numeric, static_cast<int>(x.size()), 1, x.data(), &klu_->common);
}

}  // namespace flexbody::runtime::detail
