#pragma once
// GeneralizedAlpha's state between steps and the steps themselves (the method: flexbody/runtime/generalized_alpha.hpp).
// Defined in generalized_alpha.cpp (start and Newton solver), generalized_alpha_step.cpp (steps, retries, error
// control), generalized_alpha_newton.cpp (the Newton iteration) and generalized_alpha_checkpoint.cpp (save, restore);
// the installed class forwards to it (generalized_alpha_interface.cpp).

#include "flexbody/runtime/generalized_alpha.hpp"

#include "../body/body_measures.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace flexbody::runtime {

namespace detail {
class NewtonSolver;
class ConstantCoreNewton;
class CoreInverses;
class StabilizedCoupling;
class ConstraintProjection;
class FieldPredictor;
class LocalError;
class StepController;
}  // namespace detail

class GeneralizedAlpha::Impl {
 public:
  Impl(const System& system, const GeneralizedAlphaOptions& options, double t0);
  ~Impl();
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  void step();                      ///< GeneralizedAlpha::step
  void step_to(double t_end);       ///< GeneralizedAlpha::step_to
  void step_toward(double t_stop);  ///< GeneralizedAlpha::step_toward
  [[nodiscard]] IntegratorState state() const;
  void set_state(const IntegratorState& state);
  void save(format::CheckpointData& out) const;
  void restore(const format::CheckpointData& in);
  [[nodiscard]] long rejected_steps() const;
  [[nodiscard]] long steps_above_tolerance() const;
  [[nodiscard]] double next_step() const;
  [[nodiscard]] double min_step() const;

  /// One step's constants: its size h, end time t1, β' and γ' of the Newmark update, and whether the constraints
  /// take the stabilised index-2 form.
  struct StepFrame {
    double h = 0.0, t1 = 0.0, beta_prime = 0.0, gamma_prime = 0.0;
    bool stabilized = false;
  };
  void advance(double h, double t1);  ///< one step of size h to time t1 (step, step_to)
  /// advance's work: from t_ to t1 as 2^pieces steps, a failed one in halves down to min_step().
  void cover(double h, double t1, int pieces, int depth, int& deepest);
  /// One step with its retries (a fresh matrix, the coupled step): false, the reason in `failure`, when it failed.
  bool attempt_step(double h, double t1, std::string& failure);
  void keep_step_start();               ///< the state before a step that is being taken in pieces
  void restore_step_start();            ///< back to it when a piece failed at min_step
  void load(const IntegratorState& s);  ///< the state's values become the integrator's (set_state, restore_step_start)
  void predict(const StepFrame& f);     ///< the Newton iterate's start (generalized_alpha_step.cpp)
  void predict_fields(const StepFrame& f);  ///< a GCMS body's unresolved field components: its last deformation
  void accept(const StepFrame& f);          ///< the converged iterate, checked, becomes the state
  [[nodiscard]] double estimate_step_error(const StepFrame& f);  ///< error control's estimate of the converged step [m]
  /// One attempt's Newton iterations from the predictor (generalized_alpha_newton.cpp): true when they converged;
  /// a failure's reason goes to `failure` (the first kept), `fresh` is set when a Newton matrix was built.
  bool iterate(const StepFrame& f, double extent, bool& fresh, std::string& failure);
  /// The Newton matrix at the iterate, with Φ_q W Φ_qᵀ and the coupling in the stabilised form; false (the reason
  /// in `failure`) when the iteration diverged into dependent rows or a non-finite coupling. `evaluated`: the
  /// residual was evaluated on the way.
  bool build_newton_matrix(const StepFrame& f, bool& evaluated, std::string& failure);
  void evaluate_residual(const StepFrame& f);  ///< work_.residual at the iterate: (M q̈ − f)/β' + Φ_qᵀ μ
  /// W Φ_q(q_f)ᵀ ν, along the Jacobian of the kept Newton matrix.
  void position_correction(const Eigen::VectorXd& nu, Eigen::VectorXd& out) const;
  /// `growing`: the corrections grew at the last iteration (a divergence, not a singular matrix).
  void record_divergence(double t1, const Eigen::VectorXd& phi, bool growing, std::string& failure) const;
  void build_solver(double h);  ///< the Newton solver for steps of size h (β', γ'), to be factorized
  /// The sparse coupled stabilised step's Newton matrix at the iterate (ConstantCoreNewton::factor_coupled).
  void build_sparse_coupling(double t1, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& qdd,
                             const Eigen::VectorXd& mu, double h, double gamma_prime);
  void check_deformation(double t, const Eigen::VectorXd& q) const;
  void check_spin(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v);
  [[nodiscard]] std::string last_state_diagnosis() const;

  const System& system_;
  GeneralizedAlphaOptions options_;
  double alpha_m_ = 0.0, alpha_f_ = 0.0, beta_ = 0.0, gamma_ = 0.0;
  double t0_ = 0.0, t_ = 0.0;
  long steps_ = 0;  ///< t = t0 + steps h: no accumulated rounding in the time
  Eigen::VectorXd q_, v_, qdd_, a_, lambda_;
  struct Iterate {  // step()'s Newton iterate and its residual and correction: storage reused across steps
    Eigen::VectorXd qdd, a, v, q, mu, dx, residual, predicted;
    Eigen::VectorXd phi, velocity_rows, nu, nu_step, position_step;  ///< Φ; Ψ/γ', ν, Δν, W Φ_qᵀ Δν (stabilized_index2)
    Eigen::VectorXd shift;  ///< W Φ_q(q_f)ᵀ ν: ν's whole correction in the iterate q (stabilized_index2)
    Eigen::SparseMatrix<double> jacobian;  ///< Φ_q at the iterate (System::sparse_constraint_jacobian)
    Eigen::VectorXd coupled;               ///< [δ'; Δμ; Δν] of the sparse coupled step
    /// The error estimate, M times it, it filtered, and zero constraint rows (estimate_step_error)
    Eigen::VectorXd error, error_rhs, error_dx, error_rows;
  } work_;
  /// ConstraintForm::stabilized_index2: Φ_q W Φ_qᵀ at the Newton matrix's iterate q_f, factorized (dependent rows
  /// show there), and the coupling of ν to δ and μ, kept with the Newton matrix; ν corrects the positions along
  /// W Φ_q(q_f)ᵀ, the same Jacobian (position_correction).
  std::unique_ptr<detail::ConstraintProjection> projected_;
  bool sparse_ = false;  ///< the reduced Newton matrix and Φ_q W Φ_qᵀ are factorized sparse
  std::unique_ptr<detail::StabilizedCoupling> coupling_;
  /// ConstraintForm::stabilized_index2 builds its Newton matrices with the coupled step (stabilized_coupling.hpp):
  /// set once a step failed with a fresh Newton matrix and the alternating step.
  bool couple_ = false;
  bool coupled_ = false;            ///< the kept Newton matrix was built with the coupled step
  Eigen::VectorXd nu_;              ///< the last step's ν, the next step's first guess
  bool time_dependent_ = false;     ///< a constraint depends on t (a driven joint)
  std::vector<double> body_sizes_;  ///< bounding-box diagonal of each body's mesh [m]
  /// Per body, the mass norm of its elastic displacement, checked every step (body_measures.hpp).
  std::vector<detail::ElasticMassNorm> deformations_;
  /// Per coordinate, the length scale Newton's corrections are measured in (see GeneralizedAlphaOptions::tolerance).
  Eigen::VectorXd scales_;
  /// Per coordinate, W of ConstraintForm::stabilized_index2: scale_i² / (m r²) of its body. Within a body the
  /// coordinates' own metric; between bodies 1/(m r²), so that a light body takes the position correction rather
  /// than a heavy one (with scale² alone a 1 mm bar on the tip of a 100 m bar moved the big bar, and Newton stalled).
  Eigen::VectorXd squared_scales_;
  /// Per coordinate, its scale per metre (scales_ / the body's r): how far a world position of 1 m moves it.
  Eigen::VectorXd reach_;
  double ground_extent_ = 0.0;  ///< the largest distance of a joint's ground point from the origin [m]
  std::vector<std::string> warnings_;
  std::vector<char> spin_warned_;  ///< per body: its spin warning was given
  /// Per body: System::prestress_gap at the start (empty: its spin is judged by the stiffened levels).
  std::vector<std::string> prestress_gaps_;
  /// The inputs of the last Newton matrix built (build_newton_matrix), kept so that restore() rebuilds it bit for bit:
  /// the iterate before ν's correction was turned to its Jacobian, that correction and ν, and the frame of its step.
  struct BuildPoint {
    bool valid = false;
    double t1 = 0.0, h = 0.0;
    bool couple = false;
    int iterations = 0;
    Eigen::VectorXd q, shift, nu, v, qdd, mu;
  } built_at_;
  std::unique_ptr<detail::NewtonSolver> solver_;
  std::unique_ptr<detail::CoreInverses> cores_;              ///< the constant cores' inverses of recent step sizes
  std::unique_ptr<detail::FieldPredictor> field_predictor_;  ///< a GCMS body's unresolved fields' predictor
  /// Error control (GeneralizedAlphaOptions::error_tolerance > 0; null without): the estimate, the controller, the
  /// last accepted step's estimate [m] and the largest step taken [s].
  std::unique_ptr<detail::LocalError> local_error_;
  std::unique_ptr<detail::StepController> controller_;
  double step_error_ = 0.0, largest_step_ = 0.0;
  /// a_{n−1} and h_{n−1}, the step before the last (0: none since the start or set_state): the estimate differences
  /// a over two steps (local_error.hpp).
  Eigen::VectorXd a_before_;
  double h_before_ = 0.0;
  /// step_toward's steps: the stop they are fitted to, their size [s] (0: none yet, or fitted anew at the next), and
  /// how many accepted steps in a row the controller proposed twice that size or more
  double plan_stop_ = 0.0, plan_size_ = 0.0;
  int plan_growth_ = 0;
  bool tolerance_warned_ = false;  ///< a step was accepted above the tolerance at min_step (said once)
  /// solver_ when it is the constant core with a sparse reduced matrix: its coupled stabilised step is one sparse
  /// system (ConstantCoreNewton::factor_coupled) instead of StabilizedCoupling's m solves; null otherwise.
  detail::ConstantCoreNewton* sparse_core_ = nullptr;
  double solver_step_ = 0.0;  ///< the step size solver_ was built for (its β' and γ')
  int iterations_ = 0;        ///< of the current attempt
  int step_iterations_ = 0;   ///< of the last step, all its pieces (last_iterations)
  long total_iterations_ = 0, factorizations_ = 0;
  bool refresh_ = true;       ///< build the Newton matrix at the next iteration
  int extra_iterations_ = 0;  ///< iterations beyond two per step since the Newton matrix was built
  static constexpr int kExtraIterationsPerRebuild = 10;
  /// Steps that start with a fresh Newton matrix because a matrix kept from the step before went stale within a
  /// step (the iterations spent on it are then wasted): `fresh_starts_` more steps do, and each failed trial of a
  /// kept matrix doubles the count up to kLongestFreshStarts (a long chain's coupled stabilised step needs a matrix
  /// a step: bench/README.md "scale_bench"); a kept matrix that serves a step resets it.
  int fresh_starts_ = 0, fresh_start_backoff_ = 0;
  static constexpr int kLongestFreshStarts = 16;
  /// The next step is taken in 2^split_ pieces: one less than the last step needed, so that a step that had to be
  /// halved is not first tried whole again, and the step grows back by a factor 2 per step.
  int split_ = 0;
  long retried_steps_ = 0;                                          ///< steps or pieces that failed and were halved
  double smallest_step_ = std::numeric_limits<double>::infinity();  ///< the smallest piece of a halved step
  /// The coupled step (couple_) after it rescued a step: the steps it still serves, and how many it served last time
  /// (doubled each time it is needed again, from kCoupledSteps up to kLongestCoupling).
  long coupled_steps_left_ = 0, coupled_backoff_ = 0;
  bool coupled_warned_ = false;
  static constexpr long kCoupledSteps = 8, kLongestCoupling = 1L << 20;
  /// The state at the start of a step taken in pieces (keep_step_start).
  struct StepStart {
    bool valid = false;
    IntegratorState state;
    Eigen::VectorXd a_before;
    double h_before = 0.0;
  } step_start_;
};

}  // namespace flexbody::runtime
