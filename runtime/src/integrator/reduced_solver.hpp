#pragma once
// reduced_solver.hpp (internal): the factorization of the reduced Newton matrix, the system in [Δq_r; Δμ] that is
// left after each body's ξ block has been eliminated with its constant core (newton_solvers.hpp). It is given as
// triplets (duplicates add), the way the bodies and joints contribute their blocks.
//
// Two kinds, chosen by the size of the matrix (GeneralizedAlphaOptions::reduced_solver):
// - dense: the explicit inverse, so that a solve is one product with the dense kernel. Cheapest for a few bodies
//   (a one-body pendulum's 26 rows: a 0.3 µs product), but O(size²) per solve and O(size³) per factorization.
// - sparse: SuiteSparse's KLU (Davis & Palamadai Natarajan 2010), made for circuit simulation's sequences of
//   matrices with one pattern. Each joint's rows touch two bodies, so the matrix has O(size) entries and a chain
//   or a loop keeps the factors O(size) under KLU's fill-reducing ordering (AMD on the pattern of A + Aᵀ). The
//   pattern is the union of the nonzeros seen so far (the blocks' structural zeros left out), and the ordering is
//   computed once per pattern (klu_analyze); later factorizations of the same pattern reuse the pivot
//   sequence too (klu_refactor) and fall back to a fresh pivoting factorization when its pivots have degraded.
//   bench/sparse_solver_bench measured KLU against Eigen's SparseLU and a quasi-definite SimplicialLDLT on these
//   matrices (bench/README.md, "sparse_solver_bench").
//   klu_solve works in place on KLU's own work storage: a solve allocates nothing.

#include "../kernels/dense_product.hpp"
#include "../kernels/triplet_assembly.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace flexbody::runtime::detail {

class ReducedSolver {
 public:
  virtual ~ReducedSolver() = default;
  /// Factorizes the size x size matrix whose entries are the sums of `entries` (row, column, value).
  virtual void factor(Eigen::Index size, const std::vector<Eigen::Triplet<double>>& entries) = 0;
  /// x = A⁻¹ b (x resized to b's size; not b). A singular matrix gives non-finite entries, which the integrator
  /// reports as a singular Newton matrix.
  virtual void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) = 0;
  /// What a continuation bit for bit needs beyond the matrix the next factor() is given (a checkpoint's entries,
  /// named from `prefix`): nothing for the dense solver, whose factorization depends on its matrix alone.
  virtual void save_history(std::map<std::string, std::vector<double>>& out, const std::string& prefix) const {
    (void)out, (void)prefix;
  }
  /// Restores save_history's entries: the next factor() then repeats the last one before the save exactly (its
  /// result and its effect on later factorizations). Throws std::invalid_argument naming a missing or malformed entry.
  virtual void restore_history(const std::map<std::string, std::vector<double>>& in, const std::string& prefix) {
    (void)in, (void)prefix;
  }
  /// After the factor() that repeats the saved one, or in its place when the saved build never reached factor() (it
  /// failed before): later factor() calls take their own course.
  virtual void end_replay() {}
  /// The matrix of the last factor(), sparse (for tests; the dense solver's has its size only).
  [[nodiscard]] const Eigen::SparseMatrix<double>& matrix() const { return matrix_; }

 protected:
  Eigen::SparseMatrix<double> matrix_;
};

class DenseReducedSolver final : public ReducedSolver {
 public:
  void factor(Eigen::Index size, const std::vector<Eigen::Triplet<double>>& entries) override;
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) override;

 private:
  Eigen::MatrixXd dense_;
  PaddedMatrix inverse_;
};

class SparseReducedSolver final : public ReducedSolver {
 public:
  SparseReducedSolver();
  ~SparseReducedSolver() override;
  SparseReducedSolver(const SparseReducedSolver&) = delete;
  SparseReducedSolver& operator=(const SparseReducedSolver&) = delete;
  void factor(Eigen::Index size, const std::vector<Eigen::Triplet<double>>& entries) override;
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) override;
  /// Symbolic analyses and pivoting factorizations done so far (the rest were refactorizations): for tests.
  [[nodiscard]] int analyses() const { return analyses_; }
  [[nodiscard]] int pivoting_factorizations() const { return pivoting_; }
  /// Entries of the pattern KLU factorizes (the nonzeros seen so far): for tests.
  [[nodiscard]] Eigen::Index pattern_nonzeros() const { return static_cast<Eigen::Index>(inner_.size()); }
  /// The analysed pattern, its growths, the values of the last pivoting factorization (whose pivot sequence later
  /// refactorizations keep) and how the last factor() ended.
  void save_history(std::map<std::string, std::vector<double>>& out, const std::string& prefix) const override;
  /// Analyses the saved pattern and factorizes the saved pivoting values again (the same symbolic and numeric objects
  /// as before the save); the next factor() then ends as the last one did: a refactorization with the same pivots
  /// where it was one, the numeric object as restored where it was a pivoting factorization.
  void restore_history(const std::map<std::string, std::vector<double>>& in, const std::string& prefix) override;
  void end_replay() override { replay_ = false; }

 private:
  struct Klu;  // KLU's objects, kept out of this header
  std::unique_ptr<Klu> klu_;
  /// matrix_ from `entries` (the Newton matrix's blocks come in the same order at every build).
  TripletAssembly assembly_;
  /// The matrix's values on the analysed pattern (values_); false if a nonzero lies outside it.
  bool scatter();
  /// The analysed pattern ∪ the matrix's nonzeros (only the nonzeros when `keep` is false: a new size), and its
  /// zero entries too if `with_zeros`.
  void grow_pattern(bool keep, bool with_zeros);
  int growths_ = 0;  ///< times the pattern grew at this size
  std::vector<int> outer_, inner_;  ///< the analysed pattern: every nonzero seen so far
  std::vector<double> values_;      ///< the last matrix on it
  bool singular_ = true;
  std::vector<double> pivot_values_;  ///< values_ at the last pivoting factorization that succeeded
  bool pivoted_last_ = false;  ///< the last factor() ended with a pivoting factorization (or a singular matrix)
  bool replay_ = false;  ///< restore_history ran: the next factor() keeps the restored numeric object if pivoted_last_
  double fresh_rcond_ = 0.0;  ///< KLU's pivot-ratio estimate at the last pivoting factorization
  int analyses_ = 0, pivoting_ = 0;
};

}  // namespace flexbody::runtime::detail
