#pragma once
// flexbody/runtime/generalized_alpha.hpp: the generalized-α method for the constrained equations of a System, by
// default in the stabilised index-2 form of Arnold, Cardona & Brüls (2016), with the constraint rows and multipliers
// scaled as Bottasso, Bauchau & Cardona (2007) propose so that the Newton matrix stays O(1) as h → 0, and consistent
// initial velocities, accelerations and multipliers.
//
//   q_{n+1} = q_n + h v_n + h² (½ − β) a_n + h² β a_{n+1} + W Φ_q(q̂)ᵀ ν_{n+1},
//   v_{n+1} = v_n + h (1 − γ) a_n + h γ a_{n+1},   (1 − α_m) a_{n+1} + α_m a_n = (1 − α_f) q̈_{n+1} + α_f q̈_n,
//   M q̈_{n+1} − Q(q_{n+1}) + Φ_qᵀ λ_{n+1} = 0,   Φ(q_{n+1}, t_{n+1}) = 0,   Φ_q v_{n+1} + Φ_t = 0,
//
// q̂ the iterate where the Newton matrix in use was built (within the last few steps),
// with α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1), γ = ½ + α_f − α_m, β = ¼ (γ + ½)²: second order, and
// unconditionally stable for linear problems, with high-frequency damping set by ρ∞ ∈ [0, 1]. The index-3 form
// (Arnold & Brüls 2007; ConstraintForm::index3) drops ν and the velocity rows.
// Newton corrects q; the dynamic rows are divided by β' = (1 − α_m)/(β h² (1 − α_f)) and the unknown is β'⁻¹λ.

#include "flexbody/runtime/system.hpp"

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace flexbody::format {
struct CheckpointData;
}

namespace flexbody::runtime {

/// How each Newton iteration's linear system is solved.
enum class NewtonMatrix {
  /// Eliminate each flexible body's ξ block with the factor of C = G_ff ⊗ I3 + (K̂ + γ' D̂)/β', constant for the
  /// step size (formulations.md, "The Method": the constant core): O((3 n_f)²) per right-hand side instead of O(n³).
  constant_core,
  dense,  ///< the whole matrix, LU per iteration: the reference the constant core is tested against
};

/// How the constant core's reduced Newton matrix (every body's τ and a, or all of a floating-frame body's
/// coordinates, and the constraint rows) and the stabilised form's Φ_q W Φ_qᵀ are factorized.
enum class ReducedMatrix {
  /// Sparse from kSparseFromRows reduced rows on, dense below (the measured crossover, bench/README.md "scale_bench").
  automatic,
  /// Explicit dense inverse: a solve is one dense product, O(size²); a factorization O(size³).
  dense,
  /// KLU (SuiteSparse) with its ordering computed once per run: O(size) per solve and per factorization in a chain
  /// or a ladder of loops.
  sparse,
};

/// ReducedMatrix::automatic's crossover: reduced matrices of at least this many rows are factorized sparse.
inline constexpr long kSparseFromRows = 100;

/// Which constraint equations each step solves.
enum class ConstraintForm {
  /// Φ(q_{n+1}) = 0 and Φ_q v_{n+1} + Φ_t = 0: the stabilised index-2 form of Arnold, Cardona & Brüls (2016, the
  /// GGL form of generalized-α). The velocity constraints are met at every step by the Newmark update itself, and
  /// the position constraints by a second multiplier ν that moves the positions off the Newmark update,
  /// q_{n+1} = (Newmark) + W Φ_q(q̂)ᵀ ν (q̂ where the Newton matrix was built), W = diag(scale²)/(m r²) per body
  /// (the coordinates' length scales, divided by each body's m r²; ν → 0 with h). Each Newton iteration first
  /// alternates (ν, then the dynamic rows); after a step fails that way with a fresh Newton matrix, that step and the
  /// next 8 solve δ, μ and ν together (twice as many each time it is needed again; a light carriage under a fast
  /// slider needs it; runtime/src/integrator/stabilized_coupling.hpp).
  /// Without
  /// the velocity rows the velocities drift off the hidden constraints and, at ρ∞ near 1, a spinning body gains
  /// energy and angular momentum (a heavy top at 150 rad/s diverges at ρ∞ = 1, a flipping plate gains
  /// 17.6 % energy at ρ∞ = 0.99).
  stabilized_index2,
  /// Φ(q_{n+1}) = 0 only (Arnold & Brüls 2007): one linear solve per iteration less (a product with Φ_q and a
  /// Cholesky of an m x m matrix), stable for ρ∞ < 1 only on fast spins.
  index3,
};

/// GeneralizedAlphaOptions::min_step's default: the step divided by this (six halvings).
inline constexpr double kDefaultSplits = 64.0;

/// The largest GeneralizedAlphaOptions::tolerance accepted: above it the iteration error exceeds the discretisation
/// error (bench/README.md, "convergence_bench": at 1e-4 the convergence is gone).
inline constexpr double kLargestTolerance = 1e-3;

struct GeneralizedAlphaOptions {
  NewtonMatrix newton_matrix = NewtonMatrix::constant_core;
  ReducedMatrix reduced_matrix = ReducedMatrix::automatic;  ///< constant_core only
  ConstraintForm constraints = ConstraintForm::stabilized_index2;
  double rho_infinity = 0.9;  ///< spectral radius at infinite frequency, [0, 1]
  double step = 1e-3;         ///< h [s]
  int max_iterations = 25;    ///< Newton iterations per step before the step fails
  /// A step whose Newton iteration fails (with a fresh matrix, and in the stabilised form with the coupled step) is
  /// taken again as two halves, each of which may be halved again, down to `min_step` [s] (0: step / kDefaultSplits);
  /// the steps after it start in half as many pieces each, until they are whole again. Only a failure at min_step
  /// ends the run. 0 < min_step <= step, or 0.
  double min_step = 0.0;
  /// Error control: > 0 lets step() and step_toward() choose each step's size so that generalized-α's local position
  /// error estimate per step, in metres, stays below it (runtime/src/integrator/local_error.hpp):
  ///   e = (β − γ/2 + 1/12) h² (a_{n+1} − a_{n−1}) h / (h + h_{n−1}),
  /// filtered through the Newton matrix, each coordinate measured by the world displacement it makes (a rotation at the
  /// body's radius of gyration, a field at its largest nodal displacement), the deformation only in the vibrations the
  /// step resolves; a PI controller sets the steps (step_controller.hpp). A step above it is taken again,
  /// shorter; one whose Newton iteration fails, at half its size; min_step is the floor (a step at min_step is
  /// accepted whatever its error, and counted), `step` the first step. 0: fixed steps of `step`. Not for scenes with
  /// a full-order body (no modal split of its vibrations).
  double error_tolerance = 0.0;
  double max_step = 0.0;  ///< error control's largest step [s] (0: none); at least `step`
  /// Newton's stopping test, dimensionless. Each coordinate's correction is measured in its body's length scale r
  /// (the radius of gyration √(tr J / m)): τ [m] against r, vec(A) as it is (a change δa moves a point at r by
  /// r δa), a field coordinate ξ_f against r / max_i |Ῡ'(i, f)| (the largest nodal displacement it makes). The
  /// iteration stops when its remaining error, estimated as ρ/(1 − ρ) times the last correction (ρ the observed
  /// contraction per iteration, so at least two iterations), is below `tolerance` times the step's
  /// predictor-corrector distance ‖q − q_pred‖ (β h² (1 − α_f)/(1 − α_m) ‖q̈_{n+1} − q̈_n‖, proportional to the step's
  /// local error), or when the corrections reach the round-off of the coordinate and of the world positions it moves
  /// (8 ε (|q_i| + scale_i + reach_i × the largest |τ| or joint ground point)), or stagnate within 100 times that.
  /// At most kLargestTolerance. An iteration error e in q is an acceleration error
  /// e/(β h²): a lag of about tolerance × h in the forces, far below the time discretisation error while
  /// tolerance ≪ ω h (ω the motion's frequency). bench/convergence_bench: at 1e-6 the errors of a rigid pendulum,
  /// a heavy top and a flexible pendulum agree with those at 1e-8 to 2.5 % for h = 2e-4 ... 1e-5 s; at 1e-5 they
  /// no longer do.
  double tolerance = 1e-6;
  /// Keep the Newton matrix (and its factorization) across iterations and steps, refreshing it when the
  /// corrections stop shrinking by 4× per iteration (modified Newton: fewer factorizations, the same solution in the
  /// index-3 form; in the stabilised form the kept matrix's Jacobian also sets ν's direction W Φ_q(q̂)ᵀ, which moved
  /// bench/convergence_bench's errors by −0.3 to +1.1 %).
  bool reuse_newton_matrix = true;
  /// ConstraintForm::stabilized_index2: solve δ, μ and ν together from the first step (stabilized_coupling.hpp)
  /// instead of only after a step failed with the alternating step. For scenes known to need it (a light carriage
  /// guiding a fast slider: stabilized_coupling.hpp); each Newton matrix then costs more.
  bool coupled_from_start = false;
  /// A linear model holds for small deformations only (formulations.md, "The Method": what a linear model leaves out:
  /// no geometric stiffening). A step after which a flexible body's RMS elastic displacement ‖ξ̄‖/√m exceeds this
  /// fraction of its size (the bounding-box diagonal) stops the run with a StepFailure that says so; 0 disables the
  /// check.
  double deformation_limit = 0.02;
  /// A linear corotational model has no centrifugal (geometric) stiffening, so its deformation of a body spinning at
  /// Ω is wrong by about c (Ω/ω₁)², ω₁ = 2π BodyModel::lowest_frequency_hz: c ≈ 0.36 measured in the spin plane of
  /// a clamped beam (10 % at Ω = 0.53 ω₁), c ≈ 1.2 out of it (Southwell's coefficient of a cantilever's
  /// first mode). After each step, a flexible body whose Ω/ω₁ exceeds `spin_warning` gets a line in warnings()
  /// (once), and one whose Ω/ω₁ exceeds `spin_limit` stops the run with a StepFailure that says why. 0 disables
  /// either. Bodies without a known frequency are not checked.
  double spin_warning = 0.25;  ///< Ω/ω₁: the model's error passes ~2 % (in plane) to 8 % (out of plane)
  double spin_limit = 0.5;     ///< Ω/ω₁: ~9 % (in plane) to 30 % (out of plane)
  /// The same levels for a body whose geometric stiffness covers every load on it (System::prestress_gap is empty):
  /// its stiffened model met the rotating cantilever's frequencies within 0.12 % up to Ω = 2 ω₁ in both
  /// formulations (tests/runtime/stiffening_test.cpp); beyond, the fixed basis and the terms still left out (large
  /// deformation, the modes' own change with the speed) take over: at 3-4 ω₁ the improved GCMS showed a spurious
  /// mode in the plane of rotation (its frequency off by 10-40 %; the FFRF's within 1 %).
  double stiffened_spin_warning = 2.0;  ///< Ω/ω₁: the end of the range verified against the rotating beam
  double stiffened_spin_limit = 3.0;    ///< Ω/ω₁: where the GCMS's in-plane error was first measured (10 %)
};

/// An option out of its range: its name, as a scene's `integrator` key names it (rho_inf, step, min_step, ...), and
/// why, in words that name it ("rho_inf must lie in [0, 1], got 1.5").
struct OptionProblem {
  std::string option;
  std::string message;
};

/// The first of `options` out of its range, or nothing: the one check of the options, which GeneralizedAlpha's
/// constructor throws as std::invalid_argument("generalized-alpha: " + message) and a scene's reader (fbsim, Python)
/// reports at the key's line. Ranges that need the scene (a step beyond the end time) are the reader's.
[[nodiscard]] std::optional<OptionProblem> check_options(const GeneralizedAlphaOptions& options);

/// The integrator's state between steps: what a restart or a user's controller reads and sets.
struct IntegratorState {
  double time = 0.0;       ///< t [s]
  Eigen::VectorXd q, v;    ///< coordinates and velocities (System's layout)
  Eigen::VectorXd qdd;     ///< q̈, the accelerations
  Eigen::VectorXd a;       ///< generalized-α's acceleration-like variable (Chung & Hulbert's a)
  Eigen::VectorXd lambda;  ///< the multipliers λ [N, N m, ...]
  Eigen::VectorXd nu;      ///< the stabilised index-2 form's ν of the last step (empty: none yet)
};

/// A step whose Newton iteration did not converge, or that produced a non-finite value. what() says which body
/// or constraint and why.
class StepFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class GeneralizedAlpha {
 public:
  ~GeneralizedAlpha();
  GeneralizedAlpha(const GeneralizedAlpha&) = delete;
  GeneralizedAlpha& operator=(const GeneralizedAlpha&) = delete;
  /// Starts at t0 from the system's initial coordinates and velocities (made consistent with the constraints),
  /// with consistent accelerations and multipliers ([M Φ_qᵀ; Φ_q 0] [q̈; λ] = [Q; −d/dt(Φ_q q̇ + Φ_t)]). The
  /// system is borrowed: it must outlive the integrator and not change while it runs. Throws
  /// std::invalid_argument for bad options, an initial state that violates a constraint, or redundant or
  /// contradictory constraints.
  GeneralizedAlpha(const System& system, const GeneralizedAlphaOptions& options, double t0 = 0.0);
  GeneralizedAlpha(System&&, const GeneralizedAlphaOptions&, double = 0.0) = delete;  // borrows: would dangle

  /// Advances one step of size h, taken in halves where it fails (GeneralizedAlphaOptions::min_step). Throws
  /// StepFailure when a piece fails at min_step, or the model leaves its range; that and an exception from the scene's
  /// own functions (a force's), which passes through, leave the state at the last good step.
  void step();
  /// Advances one step that ends exactly at `t_end`, for a run that must end on its end time when that is not a
  /// whole number of steps: 0 < t_end − time() ≤ h + max(kStepToSlack h, 8 ε |t_end|) (the second: the rounding of
  /// the time far from zero). A step size that differs from the one the Newton solver was built for by more than
  /// 1e-6 of it rebuilds it (a factorization of the constant core; generalized-α takes a change of h between
  /// steps, its a ≈ q̈(t + (α_m − α_f) h) then lags by O(h) for one step, a local error of O(h³) that keeps second
  /// order); a smaller difference (t_end a whole number of steps, up to rounding) keeps it, as a modified Newton
  /// matrix (reuse_newton_matrix). Later step()s take steps of h from t_end. Throws std::invalid_argument for a
  /// t_end out of that range, and StepFailure as step() does.
  void step_to(double t_end);
  /// Error control only (GeneralizedAlphaOptions::error_tolerance): one accepted step (after any taken again) toward
  /// `t_stop`, the last ending on it exactly (a CSV row's time); infinity: no stop, a step of the controller's size.
  /// The steps to a stop are equal, the largest whole fraction of what remains that the controller's proposal
  /// allows, and keep their size while they can (until a step is taken again; from one stop to the next while the
  /// proposal is within 0.9 to 1.3 times it), so that step sizes recur and their Newton cores are computed once.
  /// Throws std::logic_error without error control, std::invalid_argument for a t_stop not ahead of time(), and
  /// StepFailure as step() does.
  void step_toward(double t_stop);
  /// The relative difference of step sizes that step_to() treats as rounding.
  static constexpr double kStepToSlack = 1e-9;

  /// The state after the last step (or the start).
  [[nodiscard]] IntegratorState state() const;
  /// Continues from `state` (one of state()'s, possibly changed: a restart, a controller's correction) with a fresh
  /// Newton matrix; the next step() goes to state.time + h. Does not check that q and v meet the constraints (a
  /// changed state that does not is pulled onto them by the next step's Newton iteration, as an impulse would).
  /// Throws std::invalid_argument naming the entry for a size that is not the system's or a non-finite value.
  void set_state(const IntegratorState& state);
  /// Writes into `out` (entries "integrator.*") everything a continuation bit for bit needs: the state, the step
  /// count, the iterate where the kept Newton matrix was built (modified Newton keeps it across steps, and in the
  /// stabilised form ν's direction too), the sparse factorization's pivot history, the counters and the warnings.
  void save(format::CheckpointData& out) const;
  /// Continues from save()'s entries as if the run had never stopped: the steps that follow give the numbers the saved
  /// integrator's would have, bit for bit (the kept Newton matrix is rebuilt at its iterate). The integrator must be
  /// built for the same system and options (a scene's checkpoint checks their identity); throws
  /// std::invalid_argument naming a missing or malformed entry, or sizes, a step or ρ∞ that differ from this one's.
  void restore(const format::CheckpointData& in);
  [[nodiscard]] double time() const;
  [[nodiscard]] const Eigen::VectorXd& coordinates() const;
  [[nodiscard]] const Eigen::VectorXd& velocities() const;
  [[nodiscard]] const Eigen::VectorXd& accelerations() const;
  [[nodiscard]] const Eigen::VectorXd& multipliers() const;  ///< λ [N, N m, ...]
  /// Newton iterations of the last step (all its pieces, when it was halved).
  [[nodiscard]] int last_iterations() const;
  [[nodiscard]] long total_iterations() const;
  [[nodiscard]] long factorizations() const;  ///< Newton matrices built so far
  /// Steps (or pieces of steps) that failed and were taken again in halves (GeneralizedAlphaOptions::min_step).
  [[nodiscard]] long retried_steps() const;
  /// The smallest piece of a step taken in halves so far [s] (infinity when none was); under error control the
  /// smallest step the controller chose (steps shortened to reach a stop time not counted).
  [[nodiscard]] double smallest_step() const;
  /// Under error control: the largest step taken [s] (0 before the first), the steps taken again because their
  /// error estimate was above the tolerance, those accepted above it at min_step, the last accepted step's estimate
  /// [m], and the size the next step will try [s]. Without: 0.
  [[nodiscard]] double largest_step() const;
  [[nodiscard]] long rejected_steps() const;
  [[nodiscard]] long steps_above_tolerance() const;
  [[nodiscard]] double step_error() const;
  [[nodiscard]] double next_step() const;
  /// GeneralizedAlphaOptions::min_step, or its default when 0 [s].
  [[nodiscard]] double min_step() const;
  /// Whether the reduced Newton matrix is factorized sparse (GeneralizedAlphaOptions::reduced_matrix).
  [[nodiscard]] bool sparse() const;
  /// Lines about the model's validity, in the order they arose (GeneralizedAlphaOptions::spin_warning): a simulator
  /// shows the new ones after each step.
  [[nodiscard]] const std::vector<std::string>& warnings() const;

 private:
  class Impl;  // the state and the steps (runtime/src/integrator/generalized_alpha_impl.hpp)
  std::unique_ptr<Impl> impl_;
};

}  // namespace flexbody::runtime
