// GeneralizedAlpha: the Newton iteration of a step (Arnold and Brüls' generalized-α on the equations of motion,
// Eq. (40), and the constraint rows): the Newton matrix, the corrections of the index-3 or the stabilised index-2
// form, and the stopping test.
#include "generalized_alpha_impl.hpp"

#include "constraint_projection.hpp"
#include "finite.hpp"
#include "newton_solvers.hpp"
#include "stabilized_coupling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace flexbody::runtime {
namespace {

using detail::all_finite;

// Round-off floor of Newton's corrections, relative to |q_i| + scale_i: a constraint row's residual is a sum of a few
// products of coordinates, so its rounding is a few ε |q|, and so is the correction it asks for. Measured: the
// corrections of a flexible pendulum stagnate at 1-2 ε (|q_i| + scale_i); 8 ε stops there without a false stop.
constexpr double kRoundOffFloor = 8.0 * std::numeric_limits<double>::epsilon();
// Corrections that stagnate within this many round-off floors (~2e-12 of the positions) end the iteration.
constexpr double kStagnationFloors = 1000.0;

}  // namespace

// The position correction W Φ_q(q_f)ᵀ ν along the Jacobian of the kept Newton matrix (q_f the iterate where it was
// built, before ν's correction was turned to it), the one its factor of Φ_q W Φ_qᵀ holds: then a correction Δν
// meets the position rows up to (Φ_q(q) − Φ_q(q_f)) W Φ_q(q_f)ᵀ Δν. With the direction Φ_q(q_n) of the step's
// start and the factor from q_f, the mismatch had both Jacobians in it and, through (Φ_q W Φ_qᵀ)⁻¹, grew with the
// scene's weakest constraint mode: a chain of 64 rigid links (its out-of-plane bending) contracted by 0.86 per
// iteration and needed the coupled step at t = 0.019 s; with this direction it converges in 4.6 iterations per
// step (bench/README.md "scale_bench").
// The converged step then moves along q_f's normal rather than q_n's: bench/convergence_bench's errors changed
// by -0.3 to +1.1 % (rigid pendulum, heavy top, flexible pendulum, 4e-4 to 1e-5 s), the orders not at all.
// `work_.shift` is the whole W Φ_q(q_f)ᵀ ν in q; a new Newton matrix moves it to the new Jacobian's direction.
void GeneralizedAlpha::Impl::position_correction(const Eigen::VectorXd& nu, Eigen::VectorXd& out) const {
  out.noalias() = work_.jacobian.transpose() * nu;
  out.array() *= squared_scales_.array();
}

// Why the first attempt that diverged did: the step fails with it unless a fresh matrix or the coupled step
// (advance) gets through.
void GeneralizedAlpha::Impl::record_divergence(double t1, const Eigen::VectorXd& phi, bool growing,
                                               std::string& failure) const {
  if (!failure.empty()) return;
  const Eigen::Index m = lambda_.size();
  std::ostringstream why;
  Eigen::Index worst = 0;
  if (m > 0) phi.cwiseAbs().maxCoeff(&worst);
  why << "t = " << t1 << " s: "
      << (growing ? "the Newton iteration diverged: its corrections grew until one was not finite at iteration "
                  : "the Newton matrix is singular or the residual not finite: a correction was not finite at iteration ")
      << iterations_ << " (largest constraint residual in "
      << (m > 0 ? system_.constraint_name(worst) : std::string("none")) << ")" << last_state_diagnosis();
  failure = why.str();
}

// The scaled dynamic rows at the iterate: (M q̈ − f)/β' + Φ_qᵀ μ, Eq. (40) with the multipliers' term.
void GeneralizedAlpha::Impl::evaluate_residual(const StepFrame& f) {
  Iterate& w = work_;
  system_.dynamic_residual(f.t1, w.q, w.v, w.qdd, w.residual, false);  // a floating-frame body's in one pass
  w.residual *= 1.0 / f.beta_prime;  // a product: a division per entry costs more than the rest of this line
  system_.add_constraint_jacobian_transpose_product(f.t1, w.q, w.mu, w.residual);
  // The geometric stiffness weighted by the spin and the joint reactions at this iterate (prestress.hpp), from
  // the joints' evaluations just made.
  system_.add_prestress_residual(f.t1, w.q, w.v, w.mu, f.beta_prime, w.residual);
}

bool GeneralizedAlpha::Impl::build_newton_matrix(const StepFrame& f, bool& evaluated, std::string& failure) {
  Iterate& w = work_;
  built_at_.valid = true;  // its inputs, for restore() (a few vector copies against a factorization)
  built_at_.t1 = f.t1;
  built_at_.h = f.h;
  built_at_.couple = couple_;
  built_at_.iterations = iterations_;
  built_at_.q = w.q;
  built_at_.shift = w.shift;
  built_at_.nu = w.nu;
  built_at_.v = w.v;
  built_at_.qdd = w.qdd;
  built_at_.mu = w.mu;
  system_.sparse_constraint_jacobian(f.t1, w.q, w.jacobian);
  if (f.stabilized) {  // ν's correction so far, along the new Jacobian (position_correction)
    w.q -= w.shift;
    position_correction(w.nu, w.shift);
    w.q += w.shift;
  }
  // The coupled stabilised step with a sparse reduced matrix builds its own system (below).
  const bool sparse_coupled = f.stabilized && couple_ && sparse_core_ != nullptr;
  // A floating-frame body's tangent and the dense matrix carry K_g: weigh it at this iterate, not at the last
  // one evaluated (after a failed attempt, that one may be far off or not finite).
  if (system_.has_prestress()) system_.set_prestress(f.t1, w.q, w.v, w.mu, f.beta_prime);
  if (!sparse_coupled) solver_->factor(f.t1, w.q, w.v, w.qdd, w.mu, w.jacobian);
  if (f.stabilized) {
    if (!projected_->factor(w.jacobian, squared_scales_)) {  // Φ_q W Φ_qᵀ
      if (iterations_ > 1) {  // rows independent at the predictor lost it at a diverging iterate
        if (failure.empty())
          failure = "t = " + std::to_string(f.t1) + " s: the Newton iteration diverged: by iteration " +
                    std::to_string(iterations_) + " it had moved the bodies so far that the constraint rows were "
                    "dependent there (Φ_q W Φ_qᵀ not positive definite at the iterate; at the step's start they are "
                    "not)" + last_state_diagnosis();
        return false;
      }
      throw StepFailure("t = " + std::to_string(f.t1) + " s: the constraint rows are dependent (Φ_q W Φ_qᵀ is not "
                        "positive definite)" + last_state_diagnosis());
    }
    coupled_ = couple_;  // the coupled step, once a step failed with the alternating one (advance)
    if (sparse_coupled) {
      build_sparse_coupling(f.t1, w.q, w.v, w.qdd, w.mu, f.h, f.gamma_prime);
    } else if (coupled_) {
      evaluate_residual(f);
      evaluated = true;
      const Eigen::MatrixXd direction = squared_scales_.asDiagonal() * Eigen::MatrixXd(w.jacobian).transpose();
      if (!coupling_->build(system_, *solver_, f.t1, w.q, w.v, w.qdd, w.mu, Eigen::MatrixXd(w.jacobian), direction,
                            w.residual, scales_, f.beta_prime, f.gamma_prime, f.h)) {
        if (failure.empty())
          failure = "t = " + std::to_string(f.t1) + " s: the coupling of the position and velocity rows "
                    "(stabilised index-2) is not finite" + last_state_diagnosis();
        return false;
      }
    }
  }
  refresh_ = false;
  extra_iterations_ = 0;
  ++factorizations_;
  return true;
}

bool GeneralizedAlpha::Impl::iterate(const StepFrame& f, double extent, bool& fresh, std::string& failure) {
  const Eigen::Index n = q_.size(), m = lambda_.size();
  Iterate& w = work_;
  Eigen::VectorXd &qdd = w.qdd, &v = w.v, &q = w.q, &mu = w.mu, &dx = w.dx, &phi = w.phi;
  Eigen::VectorXd &velocity_rows = w.velocity_rows, &position_step = w.position_step;
  const bool stabilized = f.stabilized;
  double previous_correction = std::numeric_limits<double>::infinity();
  double rate = std::numeric_limits<double>::infinity();  // unknown until a second iteration measures it
  bool slow = false;  // a correction shrank less than fourfold in this attempt: the kept matrix may be stale
  for (iterations_ = 1; iterations_ <= options_.max_iterations; ++iterations_) {
    bool evaluated = false;
    const bool refresh = refresh_ || !options_.reuse_newton_matrix;
    if (refresh) {
      if (!build_newton_matrix(f, evaluated, failure)) return false;
      fresh = true;
    }
    // The rows after a new Newton matrix, which may have moved ν's correction to its Jacobian's direction.
    if (stabilized) {
      system_.constraints_and_rates(f.t1, q, v, phi, velocity_rows);  // Φ and Φ_q v, each joint evaluated once
      if (time_dependent_) system_.add_constraint_time_derivative(f.t1, q, f.h, velocity_rows);
      velocity_rows /= f.gamma_prime;
    } else {
      system_.constraints(f.t1, q, phi);
    }
    if (stabilized && !coupled_) {
      // Alternating: position rows first. The Newmark correction δ (v += γ' δ, q̈ += β' δ) will meet the velocity
      // rows, γ' Φ_q δ = −Ψ with Ψ = Φ_q v + Φ_t; the position rows are then met by ν alone: Φ_q W Φ_qᵀ Δν =
      // −Φ − Φ_q δ = −Φ + Ψ/γ'. The position moves by W Φ_qᵀ Δν before the dynamic rows are evaluated, so that δ
      // sees it in the same iteration (with the move applied one iteration late, the corrections of the two
      // cancelled and the stopping test ended the iteration early: velocities off by 6.5e-7 of 3 m/s).
      w.nu_step = velocity_rows - phi;
      projected_->solve_in_place(w.nu_step);
      position_correction(w.nu_step, position_step);
      if (!all_finite(position_step)) {
        record_divergence(f.t1, phi, std::isfinite(rate) && rate > 1.0, failure);
        return false;
      }
      w.nu += w.nu_step;
      w.shift += position_step;
      q += position_step;
      evaluate_residual(f);
      solver_->solve(q, w.residual, velocity_rows, dx);
      if (!all_finite(dx)) {
        record_divergence(f.t1, phi, std::isfinite(rate) && rate > 1.0, failure);
        return false;
      }
    } else {
      // Index-3, or the coupled stabilised step: the index-3 system's solve, then Δν from the velocity rows, which
      // couple through Z = dΦ_q/dt (stabilized_coupling.hpp).
      if (!evaluated) evaluate_residual(f);
      if (stabilized && sparse_core_) {  // the sparse coupled step: [δ'; Δμ; Δν] at once, δ = δ' − P Δν
        sparse_core_->solve_coupled(q, w.residual, phi, velocity_rows, w.coupled);
        w.nu_step = w.coupled.tail(m);
        position_correction(w.nu_step, position_step);
        dx.resize(n + m);
        dx.head(n) = w.coupled.head(n) - position_step;
        dx.tail(m) = w.coupled.segment(n, m);
        if (!all_finite(position_step) || !all_finite(dx)) {
          record_divergence(f.t1, phi, std::isfinite(rate) && rate > 1.0, failure);
          return false;
        }
        w.nu += w.nu_step;
        w.shift += position_step;
        q += position_step;
      } else {
        solver_->solve(q, w.residual, phi, dx);
        if (!all_finite(dx)) {
          record_divergence(f.t1, phi, std::isfinite(rate) && rate > 1.0, failure);
          return false;
        }
        if (stabilized) {
          coupling_->complete(dx, phi, velocity_rows, w.nu_step);
          position_correction(w.nu_step, position_step);
          if (!all_finite(position_step) || !all_finite(dx)) {
            record_divergence(f.t1, phi, std::isfinite(rate) && rate > 1.0, failure);
            return false;
          }
          w.nu += w.nu_step;
          w.shift += position_step;
          q += position_step;
        }
      }
    }
    q += dx.head(n);
    v += f.gamma_prime * dx.head(n);
    qdd += f.beta_prime * dx.head(n);
    mu += dx.tail(m);
    // The stopping test (GeneralizedAlphaOptions::tolerance), in each coordinate's length scale: the remaining
    // error ρ/(1 − ρ) |Δq| against tolerance × |q − q_pred|, or |Δq| at the round-off of the coordinate and of the
    // world positions it moves (8 ε (|q_i| + scale_i + reach_i × extent)) and, in the stabilised form, γ' |δ_i|
    // at the round-off of the velocity. |Δq_i| is |δ_i| + |W Φ_qᵀ Δν|_i: the two must not cancel in the test.
    double correction = 0.0, distance = 0.0, above_floor = 0.0;
    double above_velocity_floor = 0.0;
    const double speed = stabilized ? (v.cwiseAbs().array() / scales_.array()).maxCoeff() : 0.0;  // fastest [1/s]
    for (Eigen::Index i = 0; i < n; ++i) {
      const double step_i = std::abs(dx(i)) + (stabilized ? std::abs(position_step(i)) : 0.0), inverse = 1.0 / scales_(i);
      correction = std::max(correction, step_i * inverse);
      distance = std::max(distance, std::abs(q(i) - w.predicted(i)) * inverse);
      above_floor = std::max(above_floor, step_i / (kRoundOffFloor * (std::abs(q(i)) + scales_(i) + reach_(i) * extent)));
      if (stabilized) {
        const double velocity_step = f.gamma_prime * std::abs(dx(i));
        above_velocity_floor = std::max(above_velocity_floor, velocity_step / (kRoundOffFloor * (std::abs(v(i)) + scales_(i) * speed)));
      }
    }
    if (iterations_ > 1 && previous_correction > 0.0) rate = correction / previous_correction;
    const double remaining = rate < 1.0 ? correction * rate / (1.0 - rate) : std::numeric_limits<double>::infinity();
    // Corrections that stopped shrinking within kStagnationFloors floors are round-off of a source the floor does
    // not know: the rounding of the linear solve, whose saddle-point matrix can have a condition number of 1e14
    // (a 1 mm bar on the tip of a 100 m bar repeated a correction of 250 floors).
    const bool stagnated = iterations_ > 2 && rate > 0.5 && above_floor <= kStagnationFloors;
    const bool at_round_off = (above_floor <= 1.0 && above_velocity_floor <= 1.0) || stagnated;
    if (at_round_off || remaining <= options_.tolerance * distance) {
      // Slow contraction that ends at round-off says nothing about the matrix: keep it (the rigid
      // pendulum at h = 1e-5 s rebuilt it 121 times instead of once).
      if (at_round_off && slow) refresh_ = false;
      return true;
    }
    // Judged against a correction of the same matrix: the first one of a matrix built in this iteration follows
    // one of the stale matrix (counting it rebuilt a fresh matrix at once, two builds per step).
    if (!refresh && correction > 0.25 * previous_correction) refresh_ = slow = true;
    previous_correction = correction;
  }
  return false;
}

}  // namespace flexbody::runtime
