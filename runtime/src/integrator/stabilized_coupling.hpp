#pragma once
// stabilized_coupling.hpp (internal): the Newton step of the stabilised index-2 form (ConstraintForm::
// stabilized_index2) with its three kinds of rows coupled, from the Newton solver of [S Jᵀ; J 0] and an m x m system.
//
// One iteration corrects the Newmark increment δ (q += δ, v += γ' δ, q̈ += β' δ), the scaled multipliers μ and the
// position multipliers ν (q += P Δν, P = W Φ_q(q_f)ᵀ with q_f the iterate where the Newton matrix was built).
// Linearised, with r the scaled dynamic residual, G = ∂r/∂q, Ψ = Φ_q v + Φ_t the velocity rows and Z = ∂Ψ/∂q =
// dΦ_q/dt (the Jacobian's rate along the motion):
//
//   S δ + Jᵀ Δμ + G P Δν = −r,      J δ + J P Δν = −Φ,      (J + Z/γ') δ + (Z/γ') P Δν = −Ψ/γ'.
//
// The first two are the index-3 system with the extra right-hand side [G P; J P] Δν, so δ = δ₀ + X Δν with
// [δ₀; μ₀] = −[S Jᵀ; J 0]⁻¹ [r; Φ] and [X; Y] = −[S Jᵀ; J 0]⁻¹ [G P; J P]. Since J δ₀ = −Φ and J X = −J P, the third
// leaves, in ν alone,
//
//   (J P − (Z/γ') (X + P)) Δν = Ψ/γ' − Φ + (Z/γ') δ₀.
//
// Without Z and X this is J W Φ_q(q_f)ᵀ Δν = Ψ/γ' − Φ, the projection of the alternating step
// (generalized_alpha_newton.cpp, its factor Φ_q W Φ_qᵀ at q_f):
// Δν first, then the dynamic rows with the velocity rows at the moved positions. That alternation is cheaper (no
// solves to build) and converges in two iterations in most scenes, but not where the velocity rows move fast with the
// positions: a slider-crank whose 0.01 kg carriage (1 cm gyration radius) guides a slider at up to 11 m/s converged
// linearly, at a rate of about 0.63 per iteration at h = 1e-3 s, and failed at t = 0.431 s (at 5e-4 s: t = 0.6045 s),
// even with the exact (dense) Newton matrix rebuilt at every iteration; a 2 mm carriage of 0.5 kg failed too. The
// coupled step converges there in two iterations with a fresh matrix (2.07 per step over the run).
//
// It costs m solves and m + 1 evaluations of the dynamic residual (G P by forward differences) and three Jacobians
// each time the Newton matrix is built (a chain of four 10-mode bars, 56 rows: 3.2 ms more per build, 53 % more per
// step). So generalized-α uses it only for a step that failed with a fresh matrix and the alternating step, and the
// next 8 steps, twice as many each time it is needed again (GeneralizedAlpha::couple_), with a line in warnings(). On the slider-crank with a 0.5 kg carriage, where the alternating step
// converges (5.6 iterations per step at h = 1e-3 s, with the matrix kept), the coupled one took 5.1 iterations and
// 1.5 times as long.
// The matrix parts (X, Y, Z, the m x m factor) are kept with the Newton matrix: from an older matrix the iteration
// converges more slowly, and P, the kept matrix's, sets where the step ends (generalized_alpha_newton.cpp, position_correction).

#include "flexbody/runtime/system.hpp"

#include "newton_solvers.hpp"

#include <Eigen/Core>
#include <Eigen/LU>

namespace flexbody::runtime::detail {

/// Z/γ' = dΦ_q/dt / γ' along (1, v) at (t, q), sparse (the Jacobian's pattern); `scales` are the coordinates' length
/// scales and h the step, which set the difference step.
[[nodiscard]] Eigen::SparseMatrix<double> constraint_rate(const System& system, double t, const Eigen::VectorXd& q,
                                                          const Eigen::VectorXd& v, const Eigen::VectorXd& scales,
                                                          double h, double gamma_prime);

class StabilizedCoupling {
 public:
  /// Builds the coupling at the iterate (t, q, v, q̈, μ) for a fresh Newton matrix `solver` (factorized with the
  /// Jacobian `jacobian` there). `direction` is P = W Φ_q(q_f)ᵀ (n x m); `residual` the scaled dynamic residual r at
  /// the iterate; `scales` the coordinates' length scales (difference steps); h the step. Returns false when a part
  /// is not finite.
  bool build(const System& system, NewtonSolver& solver, double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
             const Eigen::VectorXd& qdd, const Eigen::VectorXd& mu, const Eigen::MatrixXd& jacobian,
             const Eigen::MatrixXd& direction, const Eigen::VectorXd& residual, const Eigen::VectorXd& scales,
             double beta_prime, double gamma_prime, double h);

  /// Completes one iteration: `dx` holds [δ₀; μ₀] = −[S Jᵀ; J 0]⁻¹ [r; Φ] on entry and [δ; μ] on return; `nu_step`
  /// receives Δν. `phi` is Φ and `velocity_rows` Ψ/γ' at the iterate. Allocates nothing once sizes are set.
  void complete(Eigen::VectorXd& dx, const Eigen::VectorXd& phi, const Eigen::VectorXd& velocity_rows,
                Eigen::VectorXd& nu_step);

 private:
  Eigen::MatrixXd coupling_;  ///< [X; Y] ((n + m) x m)
  Eigen::MatrixXd rate_;      ///< Z / γ' (m x n)
  Eigen::PartialPivLU<Eigen::MatrixXd> projection_;  ///< of J P − (Z/γ')(X + P)
  Eigen::VectorXd rhs_;  ///< work vector (m)
};

}  // namespace flexbody::runtime::detail
