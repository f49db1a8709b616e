#pragma once
// newton_solvers.hpp (private): the linear solve of one Newton iteration of generalized-α,
//
//   [S  Jᵀ] [Δq]     [r]
//   [J  0 ] [Δμ] = − [Φ],    S = M + (K_t + γ' C_t + Σ λ_k ∂²Φ_k/∂q²) / β',
//
// either densely (O(n³) per iteration), or with the constant core of formulations.md, "The Method": the constant core:
// the ξξ block of each flexible body is Â C Âᵀ with C = G_ff ⊗ I3 + (K̂ + γ' D̂)/β' constant for a fixed step (A
// orthogonal), so C is factorized once and every ξ block is eliminated by two triangular solves per right-hand side,
// leaving a small system in the 12 rigid coordinates per body and the constraint rows (reduced_solver.hpp: dense for a
// few bodies, sparse for many, where each joint's rows touch two bodies). Of the damping tangent C_t only the ξξ block
// Â D̂ Âᵀ enters (its coupling to ȧ only changes the convergence rate). A floating-frame body keeps all of its 7 + n_m
// coordinates in that dense system, with its exact tangent M(q) + (∂R/∂q + γ' ∂R/∂q̇)/β'.

#include "flexbody/runtime/system.hpp"

#include "../kernels/dense_product.hpp"
#include "core_inverses.hpp"
#include "reduced_solver.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>

#include <map>
#include <memory>
#include <string>

#include <vector>

namespace flexbody::runtime::detail {

class NewtonSolver {
 public:
  virtual ~NewtonSolver() = default;
  /// Builds and factorizes the Newton matrix at (t, q, q̇, q̈, μ) with the constraint Jacobian J (μ = λ/β', scaled).
  /// q̈ enters through the floating-frame bodies, whose mass matrix depends on q; t through driven joints' curvature.
  /// The Jacobian is System::sparse_constraint_jacobian's.
  virtual void factor(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& a,
                      const Eigen::VectorXd& mu, const Eigen::SparseMatrix<double>& jacobian) = 0;
  /// dx = [Δq; Δμ] for the scaled residual r and Φ with the last factorization (which may be from an earlier
  /// iterate: a modified Newton iteration; the constant core is always applied at the current A). Not const:
  /// the solvers keep their work vectors, so that an iteration allocates nothing here once sizes are set. dx must
  /// not be one of the inputs.
  virtual void solve(const Eigen::VectorXd& q, const Eigen::VectorXd& residual, const Eigen::VectorXd& phi,
                     Eigen::VectorXd& dx) = 0;
  /// What a continuation bit for bit needs beyond the iterate the next factor() is given (ReducedSolver::save_history:
  /// the sparse factorization's pivot history); nothing for a solver whose factorization depends on its matrix alone.
  virtual void save_history(std::map<std::string, std::vector<double>>& out, const std::string& prefix) const {
    (void)out, (void)prefix;
  }
  virtual void restore_history(const std::map<std::string, std::vector<double>>& in, const std::string& prefix) {
    (void)in, (void)prefix;
  }
  virtual void end_replay() {}  ///< ReducedSolver::end_replay
};

class DenseNewton final : public NewtonSolver {
 public:
  DenseNewton(const System& system, double beta_prime, double gamma_prime);
  void factor(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& a,
              const Eigen::VectorXd& mu, const Eigen::SparseMatrix<double>& jacobian) override;
  void solve(const Eigen::VectorXd& q, const Eigen::VectorXd& residual, const Eigen::VectorXd& phi,
             Eigen::VectorXd& dx) override;
  /// [S Jᵀ; J 0] of the last factor() (for tests).
  [[nodiscard]] const Eigen::MatrixXd& matrix() const { return kkt_; }

 private:
  const System& system_;
  double beta_prime_, gamma_prime_;
  Eigen::MatrixXd kkt_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
};

class ConstantCoreNewton final : public NewtonSolver {
 public:
  /// `sparse`: factorize the reduced matrix with KLU (SparseReducedSolver) instead of its dense inverse. The cores'
  /// inverses come from `cores` (computed there, or kept from an earlier step of the same size).
  ConstantCoreNewton(const System& system, double beta_prime, double gamma_prime, bool sparse, CoreInverses& cores);
  void factor(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& a,
              const Eigen::VectorXd& mu, const Eigen::SparseMatrix<double>& jacobian) override;
  void solve(const Eigen::VectorXd& q, const Eigen::VectorXd& residual, const Eigen::VectorXd& phi,
             Eigen::VectorXd& dx) override;
  void save_history(std::map<std::string, std::vector<double>>& out, const std::string& prefix) const override {
    reduced_->save_history(out, prefix);
  }
  void restore_history(const std::map<std::string, std::vector<double>>& in, const std::string& prefix) override {
    reduced_->restore_history(in, prefix);
  }
  void end_replay() override { reduced_->end_replay(); }
  /// The reduced matrix's solver (its last matrix: for tests).
  [[nodiscard]] const ReducedSolver& reduced() const { return *reduced_; }

  /// The stabilised index-2 form's coupled step (stabilized_coupling.hpp has its derivation) as one linear system,
  /// sparse, in the total position increment δ' = δ + P Δν, the multipliers' Δμ and Δν:
  ///
  ///   [S      Jᵀ   −M P] [δ' ]     [r        ]
  ///   [J      0    0   ] [Δμ ] = − [Φ        ]      P = W Φ_q(q_f)ᵀ, Z = dΦ_q/dt along the motion,
  ///   [Z/γ'   0    −J P] [Δν ]     [Ψ/γ' − Φ ]
  ///
  /// (from S δ + Jᵀ Δμ + G P Δν = −r with G = ∂r/∂q = S − M + O(damping), J δ + J P Δν = −Φ and
  /// (J + Z/γ') δ + (Z/γ') P Δν = −Ψ/γ'). Each body's ξ is eliminated with its constant core as in factor(); the
  /// rest is one sparse LU, where StabilizedCoupling builds m solves and an m x m LU (O(m n) and O(m³)).
  /// `rate` is Z/γ' (m x n, the Jacobian's pattern), `direction` P (n x m, row-major), `projected` J P (m x m).
  void factor_coupled(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& a,
                      const Eigen::VectorXd& mu, const Eigen::SparseMatrix<double>& jacobian,
                      const Eigen::SparseMatrix<double>& rate,
                      const Eigen::SparseMatrix<double, Eigen::RowMajor>& direction,
                      const Eigen::SparseMatrix<double>& projected);
  /// dx = [δ'; Δμ; Δν] (n + 2m) with the last factor_coupled(); `velocity_rows` is Ψ/γ'.
  void solve_coupled(const Eigen::VectorXd& q, const Eigen::VectorXd& residual, const Eigen::VectorXd& phi,
                     const Eigen::VectorXd& velocity_rows, Eigen::VectorXd& dx);

 private:
  // One flexible body's part of the factorization: the constraint rows that touch its ξ, coupling = [S_rf; J_f]
  // (J_f: those rows' ξ columns) and y = S_ff⁻¹ couplingᵀ at the factorization's A.
  // One flexible body's part of the factorization: its ξ rows read S_ff ξ + R [Δq_r; x(cols)] = −r_f, and ξ enters
  // the reduced rows [kept; rows] as L ξ; `left` is L ((12 + |rows|) x 3 n_f), y = S_ff⁻¹ R (3 n_f x (12 + |cols|))
  // at the factorization's A, and rows and cols are indices into the reduced system besides the body's 12 kept
  // coordinates. Without the coupled step L = [S_rf; J_f], R = Lᵀ and rows = cols (the constraint rows on ξ).
  struct Eliminated {
    Eigen::MatrixXd left, y;
    PaddedMatrix left_kernel, y_kernel;  ///< the same, stored for the product kernel
    std::vector<Eigen::Index> rows, cols;
    Eigen::VectorXd residual_solution;  ///< S_ff⁻¹ r_f of the current solve (work vector)
    Eigen::VectorXd coupled, unknowns;  ///< L S_ff⁻¹ r_f and [Δq_r; x(cols)] of the current solve (work)
    Eigen::VectorXd rotated, core_y;    ///< core_solve's work vectors (the body's own: bodies run in parallel)
  };
  struct Coupling;  // the coupled step's extra terms (factor_coupled)
  void assemble(const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& a, const Eigen::VectorXd& mu,
                const Eigen::SparseMatrix<double>& jacobian, const Coupling* coupling);
  /// The reduced system's solve and the back-substitution of every ξ, for the right-hand side already in rhs_'s
  /// constraint part; dx's coordinate part is written (dx sized by the caller).
  void solve_reduced(const Eigen::VectorXd& q, const Eigen::VectorXd& residual, Eigen::VectorXd& dx);
  /// S_ff⁻¹ x = Â C⁻¹ Âᵀ x at the orientation a: for a block of right-hand sides (factorization), and for one
  /// (x and y of 3 n_f doubles, every iteration, through the work vectors).
  [[nodiscard]] Eigen::MatrixXd core_solve(int body, const Eigen::Matrix3d& a, const Eigen::MatrixXd& x) const;
  void core_solve(int body, const Eigen::Matrix3d& a, const double* x, double* y);

  const System& system_;
  double beta_prime_, gamma_prime_;
  std::vector<PaddedMatrix> inverses_;  ///< C⁻¹ per body; empty for rigid and full-order bodies
  /// The sparse factor of C for the full-order body (null for the others).
  std::vector<std::unique_ptr<Eigen::SimplicialLLT<Eigen::SparseMatrix<double>>>> sparse_cores_;
  std::vector<Eliminated> eliminated_;
  /// Per body, where its kept coordinates start in the reduced matrix and how many there are: τ and a (12) of a
  /// GCMS body, all 7 + n_m of a floating-frame body (whose block is dense and small: nothing to eliminate).
  std::vector<Eigen::Index> kept_offset_, kept_;
  Eigen::Index kept_total_ = 0;
  Eigen::Index unknowns_ = 0;  ///< the reduced system's size: n_r + m, or n_r + 2 m for the coupled step
  std::unique_ptr<ReducedSolver> reduced_;  ///< of the matrix in [Δq_r; Δμ] left after eliminating every body's ξ
  std::vector<Eigen::Triplet<double>> entries_;  ///< that matrix's entries (work storage of factor())
  std::vector<std::vector<Eigen::Triplet<double>>> body_entries_;  ///< per body, its part of them
  Eigen::VectorXd rhs_, reduced_solution_;  ///< work vectors of solve()
};

}  // namespace flexbody::runtime::detail
