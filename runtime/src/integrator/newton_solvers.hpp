#pragma once
// newton_solvers.hpp (private): the linear solve of one Newton iteration of generalized-α,
//
//   [S  Jᵀ] [Δq]     [r]
//   [J  0 ] [Δμ] = − [Φ],    S = M + (K_t + γ' C_t + Σ λ_k ∂²Φ_k/∂q²) / β',
//
// either densely (O(n³) per iteration), or with the constant core of FORMULATION.md section 5: the ξξ block of
// each flexible body is Â C Âᵀ with C = G_ff ⊗ I3 + (K̂ + γ' D̂)/β' constant for a fixed step (A orthogonal), so C is
// factorized once and every ξ block is eliminated by two triangular solves per right-hand side, leaving a small
// dense system in the 12 rigid coordinates per body and the constraint rows. Of the damping tangent C_t only the
// ξξ block Â D̂ Âᵀ enters (its coupling to ȧ only changes the convergence rate).

#include "flexbody/runtime/system.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <vector>

namespace flexbody::runtime::detail {

class NewtonSolver {
 public:
  virtual ~NewtonSolver() = default;
  /// Returns [Δq; Δμ] for the scaled multipliers μ = λ/β' at (t, q), given the scaled residual r and Φ, J.
  [[nodiscard]] virtual Eigen::VectorXd solve(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                                              const Eigen::VectorXd& residual, const Eigen::VectorXd& phi,
                                              const Eigen::MatrixXd& jacobian) = 0;
};

class DenseNewton final : public NewtonSolver {
 public:
  DenseNewton(const System& system, double beta_prime, double gamma_prime);
  Eigen::VectorXd solve(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& mu, const Eigen::VectorXd& residual,
                        const Eigen::VectorXd& phi, const Eigen::MatrixXd& jacobian) override;

 private:
  const System& system_;
  double beta_prime_, gamma_prime_;
  Eigen::MatrixXd mass_;
};

class ConstantCoreNewton final : public NewtonSolver {
 public:
  ConstantCoreNewton(const System& system, double beta_prime, double gamma_prime);
  Eigen::VectorXd solve(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& mu, const Eigen::VectorXd& residual,
                        const Eigen::VectorXd& phi, const Eigen::MatrixXd& jacobian) override;

 private:
  const System& system_;
  double beta_prime_;
  std::vector<Eigen::LLT<Eigen::MatrixXd>> cores_;  ///< per body; empty factor for rigid bodies
};

}  // namespace flexbody::runtime::detail
