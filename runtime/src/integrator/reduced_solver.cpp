#include "reduced_solver.hpp"

#include <klu.h>

#include <Eigen/LU>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

namespace flexbody::runtime::detail {
namespace {

// A refactorization keeps the pivot sequence of the last pivoting factorization. Its pivots have degraded when
// KLU's pivot ratio min |u_ii| / max |u_ii| falls this far below what the pivoting factorization reached; then
// the matrix is factorized afresh with partial pivoting (KLU's default threshold, 0.001).
constexpr double kPivotDegradation = 1e-3;
// SparseReducedSolver's pattern grows with the nonzeros this many times at most; then it takes the blocks' zeros too.
constexpr int kMostGrowths = 3;

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
  // COLAMD on the matrix itself, without the block triangular form: KLU's default (BTF, then AMD on A + Aᵀ) took
  // 250 ms to analyse a 1024-link rigid chain (its matching grew like N² on the saddle point's zero block) and AMD
  // without BTF filled 23 times more; COLAMD without BTF analysed it in 4 ms and refactorized in 2.5 ms against
  // 3.1 (bench/sparse_solver_bench, bench/README.md).
  klu_->common.ordering = 1;
  klu_->common.btf = 0;
}

SparseReducedSolver::~SparseReducedSolver() { klu_->free_all(); }

void SparseReducedSolver::factor(Eigen::Index size, const std::vector<Eigen::Triplet<double>>& entries) {
  if (size > std::numeric_limits<int>::max() / 2)
    throw std::runtime_error("the reduced Newton matrix has more rows than KLU's 32-bit indices take");
  assembly_.assemble(size, size, entries, matrix_);
  const int n = static_cast<int>(size);
  // KLU factorizes on the union of the nonzeros of every matrix so far, not on the blocks' dense pattern: a rigid
  // body's blocks are (G ⊗ I3)-shaped, two thirds zeros, and dropping them cut KLU's refactorization of a 1024-link
  // rigid chain's matrix from 7.1 to 0.65 ms (bench/sparse_solver_bench). An entry that turns nonzero later (a
  // rotation away from the axes, a multiplier) grows the union and triggers a new analysis: a few per run.
  const bool same_size = klu_->symbolic && outer_.size() == static_cast<std::size_t>(n + 1);
  if (!same_size || !scatter()) {
    // A pattern that keeps growing (the coupled stabilised step's entries turn nonzero one by one as the bodies
    // start to move: 29 analyses in 200 steps of a 64-link chain) takes every entry the blocks hold from its
    // kMostGrowths-th growth on, zeros included, so that the analyses stop.
    growths_ = same_size ? growths_ + 1 : 0;
    grow_pattern(same_size, growths_ >= kMostGrowths);
    klu_->free_all();
    klu_->symbolic = klu_analyze(n, outer_.data(), inner_.data(), &klu_->common);
    ++analyses_;
    if (!klu_->symbolic) throw std::runtime_error("KLU could not analyse the reduced Newton matrix (status " +
                                                  std::to_string(klu_->common.status) + ")");
    scatter();
  }
  int* outer = outer_.data();
  int* inner = inner_.data();
  double* values = values_.data();
  const bool replay = std::exchange(replay_, false);
  if (replay && pivoted_last_) return;  // restore_history's pivoting factorization of these values is this one's
  singular_ = true;
  pivoted_last_ = false;
  if (klu_->numeric && klu_refactor(outer, inner, values, klu_->symbolic, klu_->numeric, &klu_->common) &&
      klu_rcond(klu_->symbolic, klu_->numeric, &klu_->common) && klu_->common.rcond >= kPivotDegradation * fresh_rcond_) {
    singular_ = false;
    return;
  }
  klu_->free_numeric();
  klu_->numeric = klu_factor(outer, inner, values, klu_->symbolic, &klu_->common);
  ++pivoting_;
  pivoted_last_ = true;
  if (klu_->numeric) pivot_values_ = values_;
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

void SparseReducedSolver::save_history(std::map<std::string, std::vector<double>>& out, const std::string& prefix) const {
  out[prefix + "outer"].assign(outer_.begin(), outer_.end());
  out[prefix + "inner"].assign(inner_.begin(), inner_.end());
  out[prefix + "pivot_values"] = klu_->numeric ? pivot_values_ : std::vector<double>();
  out[prefix + "state"] = {static_cast<double>(growths_), klu_->numeric ? 1.0 : 0.0, pivoted_last_ ? 1.0 : 0.0,
                           singular_ ? 1.0 : 0.0, fresh_rcond_, static_cast<double>(analyses_),
                           static_cast<double>(pivoting_)};
}

void SparseReducedSolver::restore_history(const std::map<std::string, std::vector<double>>& in, const std::string& prefix) {
  auto entry = [&](const char* name) -> const std::vector<double>& {
    const auto found = in.find(prefix + name);
    if (found == in.end()) throw std::invalid_argument("checkpoint: missing entry " + prefix + name);
    return found->second;
  };
  const std::vector<double>& outer = entry("outer");
  const std::vector<double>& inner = entry("inner");
  const std::vector<double>& state = entry("state");
  const std::vector<double>& pivot = entry("pivot_values");
  if (state.size() != 7) throw std::invalid_argument("checkpoint: " + prefix + "state has " + std::to_string(state.size()) + " entries, not 7");
  klu_->free_all();
  outer_.assign(outer.begin(), outer.end());
  inner_.assign(inner.begin(), inner.end());
  growths_ = static_cast<int>(state[0]);
  pivoted_last_ = state[2] != 0.0;
  singular_ = state[3] != 0.0;
  fresh_rcond_ = state[4];
  analyses_ = static_cast<int>(state[5]);
  pivoting_ = static_cast<int>(state[6]);
  pivot_values_ = pivot;
  replay_ = true;
  if (outer_.empty()) return;  // nothing factorized yet
  const int n = static_cast<int>(outer_.size()) - 1;
  if (n < 1 || outer_.front() != 0 || static_cast<std::size_t>(outer_.back()) != inner_.size() ||
      !std::is_sorted(outer_.begin(), outer_.end()) ||
      std::any_of(inner_.begin(), inner_.end(), [n](int i) { return i < 0 || i >= n; }))
    throw std::invalid_argument("checkpoint: " + prefix + "outer and inner are not a sparse pattern");
  klu_->symbolic = klu_analyze(n, outer_.data(), inner_.data(), &klu_->common);
  if (!klu_->symbolic) throw std::invalid_argument("checkpoint: KLU could not analyse the pattern " + prefix + "inner");
  if (state[1] == 0.0) return;  // the last factorization found the matrix singular: no numeric object
  if (pivot_values_.size() != inner_.size())
    throw std::invalid_argument("checkpoint: " + prefix + "pivot_values does not match the pattern");
  klu_->numeric = klu_factor(outer_.data(), inner_.data(), pivot_values_.data(), klu_->symbolic, &klu_->common);
  if (!klu_->numeric) throw std::invalid_argument("checkpoint: KLU could not factorize " + prefix + "pivot_values again");
}

bool SparseReducedSolver::scatter() {
  values_.assign(inner_.size(), 0.0);
  const int* outer = matrix_.outerIndexPtr();
  const int* inner = matrix_.innerIndexPtr();
  const double* values = matrix_.valuePtr();
  for (Eigen::Index c = 0; c < matrix_.cols(); ++c) {
    int p = outer_[static_cast<std::size_t>(c)];
    const int end = outer_[static_cast<std::size_t>(c) + 1];
    for (int k = outer[c]; k < outer[c + 1]; ++k) {
      if (values[k] == 0.0) continue;
      while (p < end && inner_[static_cast<std::size_t>(p)] < inner[k]) ++p;
      if (p == end || inner_[static_cast<std::size_t>(p)] != inner[k]) return false;  // outside the pattern
      values_[static_cast<std::size_t>(p)] = values[k];
    }
  }
  return true;
}

void SparseReducedSolver::grow_pattern(bool keep, bool with_zeros) {
  std::vector<int> outer, inner;
  outer.reserve(static_cast<std::size_t>(matrix_.cols()) + 1);
  inner.reserve(static_cast<std::size_t>(matrix_.nonZeros()));
  outer.push_back(0);
  const int* m_outer = matrix_.outerIndexPtr();
  const int* m_inner = matrix_.innerIndexPtr();
  const double* m_values = matrix_.valuePtr();
  for (Eigen::Index c = 0; c < matrix_.cols(); ++c) {  // the sorted merge of the kept column and the new nonzeros
    int p = keep ? outer_[static_cast<std::size_t>(c)] : 0;
    const int end = keep ? outer_[static_cast<std::size_t>(c) + 1] : 0;
    for (int k = m_outer[c]; k < m_outer[c + 1]; ++k) {
      if (m_values[k] == 0.0 && !with_zeros) continue;
      while (p < end && inner_[static_cast<std::size_t>(p)] < m_inner[k]) inner.push_back(inner_[static_cast<std::size_t>(p++)]);
      if (p < end && inner_[static_cast<std::size_t>(p)] == m_inner[k]) ++p;
      inner.push_back(m_inner[k]);
    }
    while (p < end) inner.push_back(inner_[static_cast<std::size_t>(p++)]);
    outer.push_back(static_cast<int>(inner.size()));
  }
  outer_ = std::move(outer);
  inner_ = std::move(inner);
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
