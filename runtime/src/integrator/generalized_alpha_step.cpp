// GeneralizedAlpha: one step (the predictor, the retries of a step whose Newton iteration fails, the new state) and
// the checks of the model's validity after it (the deformation and spin limits).
#include "generalized_alpha_impl.hpp"

#include "../body/body_measures.hpp"
#include "field_predictor.hpp"
#include "finite.hpp"
#include "local_error.hpp"
#include "newton_solvers.hpp"
#include "step_controller.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace flexbody::runtime {
namespace {

using detail::all_finite;

// A step within this relative difference of the size the Newton solver was built for keeps the solver: its matrix is
// then off by as much, which a modified Newton iteration does not notice, and the rounding by which equal steps miss
// their stop (about their count times ulp(t), 1e-8 of a 0.1 ms step after a thousand steps at t = 10 s) builds no new
// constant cores.
constexpr double kSameStep = 1e-6;

}  // namespace

void GeneralizedAlpha::Impl::check_deformation(double t, const Eigen::VectorXd& q) const {
  if (!(options_.deformation_limit > 0.0)) return;
  for (int b = 0; b < system_.body_count(); ++b) {
    const BodyModel& model = system_.model(b);
    if (model.rigid()) continue;
    const double squared =
        deformations_[static_cast<std::size_t>(b)].squared(q.segment(system_.offset(b), model.coordinate_count()));
    const double rms = std::sqrt(std::max(squared, 0.0) / model.mass);
    const double size = body_sizes_[static_cast<std::size_t>(b)];
    if (rms > options_.deformation_limit * size) {
      std::ostringstream why;
      why << "t = " << t << " s: body '" << system_.body_name(b) << "' left the small-deformation range of its linear "
          << "model: RMS elastic displacement " << rms << " m = " << 100.0 * rms / size << " % of its size (limit "
          << 100.0 * options_.deformation_limit << " %). ";
      if (prestress_gaps_[static_cast<std::size_t>(b)].empty())
        why << "Its model is linear in the deformation (its geometric stiffening covers the prestress, not large "
            << "deformation): a load beyond linear elasticity, or a spin beyond the stiffened model's range";
      else
        why << "The model has no geometric stiffening for it (docs/formulations.md, Geometric Stiffening): "
            << "a spin above the first bending frequency, or a load beyond linear elasticity";
      throw StepFailure(why.str());
    }
  }
}

void GeneralizedAlpha::Impl::check_spin(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  for (int b = 0; b < system_.body_count(); ++b) {
    const BodyModel& model = system_.model(b);
    if (model.rigid() || !(model.lowest_frequency_hz > 0.0)) continue;
    const std::string& gap = prestress_gaps_[static_cast<std::size_t>(b)];
    const bool stiffened = gap.empty();
    const double warning = stiffened ? options_.stiffened_spin_warning : options_.spin_warning;
    const double limit = stiffened ? options_.stiffened_spin_limit : options_.spin_limit;
    if (!(warning > 0.0) && !(limit > 0.0)) continue;
    const double spin = system_.angular_velocity(b, q, v).norm();
    const double ratio = spin / (2.0 * std::numbers::pi * model.lowest_frequency_hz);
    const bool over_limit = limit > 0.0 && ratio > limit;
    const bool warn = warning > 0.0 && ratio > warning && !spin_warned_[static_cast<std::size_t>(b)];
    if (!over_limit && !warn) continue;  // the message only when it is said: this runs every step
    std::ostringstream what;
    what << "t = " << t << " s: body '" << system_.body_name(b) << "' spins at " << spin << " rad/s = " << ratio
         << " of its lowest elastic frequency (" << model.lowest_frequency_hz << " Hz); ";
    if (stiffened) {
      what
          << "its geometric stiffening was verified up to 2 times that frequency (a rotating cantilever within "
          << "0.12 %); beyond, the fixed modes and the terms still left out (large deformation, the modes' change with "
          << "the speed) limit it, and the improved GCMS showed a spurious mode in the plane of rotation at 3-4 times "
          << "it (docs/formulations.md, Geometric Stiffening)";
    } else {
      what << "a linear corotational model has no centrifugal stiffening (docs/formulations.md, Geometric Stiffening), "
           << "so its deformation is wrong by about " << 100.0 * 0.36 * ratio * ratio << " % in the spin plane and "
           << 100.0 * 1.2 * ratio * ratio << " % out of it";
      if (model.prestress) what << " (" << gap << ")";
    }
    if (over_limit) {
      what << " (limit: " << limit << " of it)";
      throw StepFailure(what.str());
    }
    spin_warned_[static_cast<std::size_t>(b)] = 1;
    what << " (warning above " << warning << " of it)";
    warnings_.push_back(what.str());
  }
}

// Why a step may have failed, from the last converged state (the failed iterate says nothing reliable): the body
// that turned most per step, and the one closest to the deformation limit.
std::string GeneralizedAlpha::Impl::last_state_diagnosis() const {
  const double h = solver_step_;  // the step or piece that failed
  int fastest = -1, most_deformed = -1;
  double largest_turn = 0.0, largest_share = 0.0, rms_of_most = 0.0;
  for (int b = 0; b < system_.body_count(); ++b) {
    const double turn = system_.angular_velocity(b, q_, v_).norm() * h;
    if (!(turn <= largest_turn)) largest_turn = turn, fastest = b;  // a non-finite rate is the one to report
    const BodyModel& model = system_.model(b);
    const double size = body_sizes_[static_cast<std::size_t>(b)];
    if (model.rigid() || !(size > 0.0)) continue;
    const double squared =
        detail::elastic_mass_norm_squared(model, q_.segment(system_.offset(b), model.coordinate_count()));
    const double rms = std::sqrt(std::max(squared, 0.0) / model.mass);
    if (!(rms / size < largest_share)) largest_share = rms / size, most_deformed = b, rms_of_most = rms;
  }
  std::ostringstream out;
  out << "; at the last converged step, t = " << t_ << " s,";
  if (fastest >= 0)
    out << " body '" << system_.body_name(fastest) << "' turned " << largest_turn << " rad per step"
        << (largest_turn > 0.1 ? " (more than 0.1 rad per step: try a smaller step)" : "");
  if (most_deformed >= 0)
    out << (fastest >= 0 ? " and" : "") << " body '" << system_.body_name(most_deformed) << "' had an RMS elastic "
        << "displacement of " << rms_of_most << " m = " << 100.0 * largest_share << " % of its size ("
        << (options_.deformation_limit > 0.0 ? "limit " + std::to_string(100.0 * options_.deformation_limit) + " %"
                                             : std::string("no limit set")) << ")";
  if (fastest < 0 && most_deformed < 0) out << " every body was at rest and undeformed";
  return out.str();
}

void GeneralizedAlpha::Impl::step() {
  if (controller_) {
    step_toward(std::numeric_limits<double>::infinity());
    return;
  }
  advance(options_.step, t0_ + static_cast<double>(steps_ + 1) * options_.step);
  ++steps_;
}

// Error control: attempts from the step's start until one is accepted (local_error.hpp, step_controller.hpp), of the
// size the plan below chooses: the proposal or less when the steps are fitted anew, a kept size otherwise (which may
// be larger than the proposal: up to 1 / kKeepBelow of it from one stop to the next, any between two stops).
void GeneralizedAlpha::Impl::step_toward(double t_stop) {
  if (!controller_)
    throw std::logic_error("generalized-alpha: step_toward needs error control (GeneralizedAlphaOptions::error_tolerance)");
  const double remaining = t_stop - t_;
  if (!(remaining > 8.0 * std::numeric_limits<double>::epsilon() * std::abs(t_stop)) && t_stop != std::numeric_limits<double>::infinity())
    throw std::invalid_argument("generalized-alpha: step_toward(" + std::to_string(t_stop) + ") from t = " +
                                std::to_string(t_) + " s is not ahead");
  keep_step_start();
  const long iterations_before = total_iterations_;
  try {
    for (;;) {
      const double proposal = controller_->proposal();
      double h = proposal, t1 = t_ + proposal;
      bool kept_size = false;
      if (!std::isfinite(remaining)) {
        plan_size_ = 0.0;  // no stop, no plan: the steps are the controller's
        plan_growth_ = 0;
      } else {
        // The steps to a stop are equal, a whole number of them in what remains, and keep their size while they can:
        // between two stops unless a step is taken again (its error above the tolerance, or its iteration failed)
        // or the proposal is twice the size or more after two steps in a row (the first steps' growth; one small
        // estimate, where the error's leading term changes sign, is not enough); from one stop to the next while
        // the proposal is within [kKeepBelow, kKeepAbove] times it (kKeepBelow = 0.9: an estimate at the controller's
        // aim, 0.73 E, is then at most E for the kept size; kKeepAbove = 1.3: at most 30 % more steps than asked).
        // A size that changes is the largest whole fraction of what remains that the proposal allows. So sizes
        // recur and change seldom, and each size's Newton cores are computed once (core_inverses.hpp); a smaller
        // step the controller asks for between two stops waits for the stop or for a step above the tolerance.
        constexpr double kKeepBelow = 0.9, kKeepAbove = 1.3;
        const bool keep = plan_size_ > 0.0 && !controller_->after_rejection() &&
                          (plan_stop_ == t_stop ? !(plan_growth_ >= 2 && proposal >= 2.0 * plan_size_)
                                                : proposal >= kKeepBelow * plan_size_ && proposal <= kKeepAbove * plan_size_);
        const double count = keep ? remaining / plan_size_ : 0.0;  // a whole number of kept steps, up to rounding
        const double whole = std::round(count);
        kept_size = whole >= 1.0 && std::abs(count - whole) < 1e-6;
        const double size = kept_size ? plan_size_ : remaining / std::max(1.0, std::ceil(remaining / proposal - 1e-6));
        if (size != plan_size_) plan_growth_ = 0;
        plan_stop_ = t_stop;
        plan_size_ = size;
        h = size;
        t1 = t_ + size;
        // The last step ends on the stop: the sum of equal steps drifts from it by their rounding (about count ulp(t)).
        if ((kept_size && whole == 1.0) || remaining <= size * (1.0 + kStepToSlack)) {
          h = remaining;
          t1 = t_stop;
        }
      }
      std::string failure;
      if (!attempt_step(h, t1, failure)) {  // nothing was accepted: the state is the step's start
        if (h <= controller_->min_step() * (1.0 + kStepToSlack)) {
          std::ostringstream why;
          why << failure << " (a step of h = " << h << " s from t = " << t_ << " s, at min_step = "
              << controller_->min_step() << " s)";
          throw StepFailure(why.str());
        }
        ++retried_steps_;
        controller_->failed(h);
        continue;
      }
      if (controller_->judge(h, step_error_)) {
        if (plan_size_ > 0.0) plan_growth_ = controller_->proposal() >= 2.0 * plan_size_ ? std::min(plan_growth_ + 1, 2) : 0;
        if (kept_size || h >= 0.5 * proposal) {  // not a stop's remainder far below what the controller asked
          smallest_step_ = std::min(smallest_step_, h);
          largest_step_ = std::max(largest_step_, h);
        }
        if (step_error_ > options_.error_tolerance && !tolerance_warned_) {
          tolerance_warned_ = true;
          std::ostringstream what;
          what << "t = " << t_ << " s: a step at min_step = " << controller_->min_step() << " s had a local error "
               << "estimate of " << step_error_ << " m, above error_tolerance = " << options_.error_tolerance
               << " m, and was accepted (such steps are counted in the summary): lower min_step, or raise the tolerance";
          warnings_.push_back(what.str());
        }
        break;
      }
      restore_step_start();  // rejected: again from the start, shorter
      keep_step_start();
    }
    step_iterations_ = static_cast<int>(total_iterations_ - iterations_before);
  } catch (...) {
    restore_step_start();
    refresh_ = true;
    plan_size_ = 0.0;
    plan_growth_ = 0;
    throw;
  }
  step_start_.valid = false;
  t0_ = t_;  // a step() without error control would count from here
  steps_ = 0;
}

long GeneralizedAlpha::Impl::rejected_steps() const { return controller_ ? controller_->rejected() : 0; }
long GeneralizedAlpha::Impl::steps_above_tolerance() const { return controller_ ? controller_->above_tolerance() : 0; }
double GeneralizedAlpha::Impl::next_step() const { return controller_ ? controller_->proposal() : options_.step; }

IntegratorState GeneralizedAlpha::Impl::state() const { return {t_, q_, v_, qdd_, a_, lambda_, nu_}; }

void GeneralizedAlpha::Impl::set_state(const IntegratorState& s) {
  const Eigen::Index n = q_.size(), m = lambda_.size();
  auto check = [](const char* name, const Eigen::VectorXd& x, Eigen::Index size) {
    if (x.size() != size)
      throw std::invalid_argument(std::string("generalized-alpha state: ") + name + " has " + std::to_string(x.size()) +
                                  " entries, the system " + std::to_string(size));
    if (!x.allFinite()) throw std::invalid_argument(std::string("generalized-alpha state: ") + name + " is not finite");
  };
  check("q", s.q, n);
  check("v", s.v, n);
  check("qdd", s.qdd, n);
  check("a", s.a, n);
  check("lambda", s.lambda, m);
  if (s.nu.size() > 0) check("nu", s.nu, m);
  if (!std::isfinite(s.time)) throw std::invalid_argument("generalized-alpha state: the time is not finite");
  load(s);
  t0_ = s.time;
  steps_ = 0;
  h_before_ = 0.0;  // the error estimate starts over
  plan_size_ = 0.0;  // and step_toward's steps are fitted anew
  plan_growth_ = 0;
  split_ = 0;
  refresh_ = true;  // the kept Newton matrix belongs to another state
  fresh_starts_ = fresh_start_backoff_ = 0;
}

void GeneralizedAlpha::Impl::step_to(double t_end) {
  if (controller_) {  // the steps the controller chooses, the last ending on t_end
    if (!(t_end > t_)) throw std::invalid_argument("generalized-alpha: step_to(" + std::to_string(t_end) + ") from t = " +
                                                   std::to_string(t_) + " s is not ahead");
    while (t_ != t_end) step_toward(t_end);
    return;
  }
  const double h = t_end - t_;
  // t_ after many steps carries the rounding of t0 + k h, about ε |t_end|: beyond 1e7 steps that exceeds 1e-9 h.
  const double slack = std::max(kStepToSlack * options_.step, 8.0 * std::numeric_limits<double>::epsilon() * std::abs(t_end));
  if (!(h > 0.0) || !(h <= options_.step + slack))
    throw std::invalid_argument("generalized-alpha: step_to(" + std::to_string(t_end) + ") from t = " +
                                std::to_string(t_) + " s is not a step of at most " + std::to_string(options_.step) +
                                " s forward");
  advance(h, t_end);
  t0_ = t_end;  // later steps: t0 + k h from here
  steps_ = 0;
}

// A GCMS body's field components that the step does not resolve start at the last step's deformation
// (field_predictor.hpp); their a, v and q̈ follow from the Newmark update. The sample bracket pendulum's first step
// at h = 8 ms predicted ‖ξ‖ = 7.4e-5 with q̈_{n+1} = q̈_n where the step ends at 8.9e-9, and the Newton matrix built
// there coupled the rotation to the fields (K_aξ ∝ K̂ ξ̄, Eq. (86)) 2.4e4 times β' M where the solution's coupling is
// 3.2 times it: Newton diverged at 4 and 8 ms. Only the start moves: the step's equations and the stopping test's
// predictor-corrector distance (w.predicted) are unchanged.
void GeneralizedAlpha::Impl::predict_fields(const StepFrame& f) {
  Iterate& w = work_;
  const double h = f.h, h2 = h * h;
  field_predictor_->apply(q_, w.q, [&](Eigen::Index first, Eigen::Index count) {
    auto a1 = w.a.segment(first, count);
    a1 = (w.q.segment(first, count) - q_.segment(first, count) - h * v_.segment(first, count) -
          h2 * (0.5 - beta_) * a_.segment(first, count)) / (beta_ * h2);
    w.v.segment(first, count) = v_.segment(first, count) + h * (1.0 - gamma_) * a_.segment(first, count) + h * gamma_ * a1;
    w.qdd.segment(first, count) = ((1.0 - alpha_m_) * a1 + alpha_m_ * a_.segment(first, count) -
                                   alpha_f_ * qdd_.segment(first, count)) / (1.0 - alpha_f_);
  });
}

// The Newton iterate's start, the predictor q̈_{n+1} = q̈_n, through the Newmark update (a GCMS body's fields:
// predict_fields); in the stabilised form moved by the last step's ν along the last Jacobian built.
void GeneralizedAlpha::Impl::predict(const StepFrame& f) {
  Iterate& w = work_;
  const double h = f.h;
  w.qdd = qdd_;
  w.a = (alpha_f_ * qdd_ - alpha_m_ * a_ + (1.0 - alpha_f_) * w.qdd) / (1.0 - alpha_m_);
  w.v = v_ + h * (1.0 - gamma_) * a_ + h * gamma_ * w.a;
  w.q = q_ + h * v_ + h * h * (0.5 - beta_) * a_ + h * h * beta_ * w.a;
  w.mu = lambda_ / f.beta_prime;  // the scaled multipliers
  w.predicted = w.q;
  predict_fields(f);
  if (f.stabilized) {
    // ν changes slowly from step to step (it is the Newmark update's drift off Φ = 0 over one step): starting from
    // the last step's ν leaves the first iteration a small Δν, whose effect on the dynamic rows is only seen at the
    // next iteration (measured: a flexible pendulum needed 3.1-3.6 iterations per step from ν = 0).
    const Eigen::Index m = lambda_.size();
    if (nu_.size() != m) nu_ = Eigen::VectorXd::Zero(m);
    w.nu = nu_;
    if (w.jacobian.rows() == m)
      position_correction(nu_, w.shift);
    else
      w.shift.setZero(q_.size());  // the first step: no Newton matrix yet, and ν = 0
    w.q += w.shift;
  }
}

void GeneralizedAlpha::Impl::advance(double h, double t1) {
  step_start_.valid = false;
  if (split_ > 0) keep_step_start();
  const long iterations_before = total_iterations_;
  try {
    int deepest = 0;
    cover(h, t1, split_, 0, deepest);
    split_ = std::max(deepest - 1, 0);  // the next step in half as many pieces: the step grows back
    step_iterations_ = static_cast<int>(total_iterations_ - iterations_before);
  } catch (...) {
    // A failure at min_step, of the model's validity, or a scene function's exception: back to the step's start if
    // pieces of it were accepted (accept() is the only other writer), so that time and state stay on the step grid;
    // a Newton matrix the failure may have left half built is not used again.
    restore_step_start();
    refresh_ = true;
    throw;
  }
}

// The step's local error estimate [m] (local_error.hpp), over two steps where there were two, seen through the Newton
// matrix: Δ = S⁻¹ M e with S = M + (γ'/β') D + K/β' (+ the constraint rows, Φ_q Δ = 0), as stiff solvers filter
// theirs (Hairer & Wanner, Solving ODEs II, IV.8, Radau5's (I − h γ₀ J)⁻¹): a vibration the step resolves,
// ω² ≪ β', passes, one it does not is divided by about β h² ω², and an error along a constraint's normal is not
// an error of the constrained motion. Without it, the bracket pendulum's 2 kHz vibration (6e-8 m after the sudden
// gravity) reached the rigid motion's estimate through the pivot, and at 1e-8 m the step changed 4 times in 5 steps.
double GeneralizedAlpha::Impl::estimate_step_error(const StepFrame& f) {
  Iterate& w = work_;
  const Eigen::Index n = q_.size(), m = lambda_.size();
  const bool two = h_before_ > 0.0;
  local_error_->estimate(two ? a_before_ : a_, w.a, f.h, two ? f.h + h_before_ : f.h, w.error);
  a_before_ = a_;
  h_before_ = f.h;
  w.error_rhs = system_.mass_product(w.q, w.error);
  w.error_rows.setZero(m);
  if (f.stabilized && coupled_ && sparse_core_ != nullptr) {
    sparse_core_->solve_coupled(w.q, w.error_rhs, w.error_rows, w.error_rows, w.coupled);
    position_correction(w.coupled.tail(m), w.error_dx);
    w.error_dx = w.coupled.head(n) - w.error_dx;
  } else {
    solver_->solve(w.q, w.error_rhs, w.error_rows, w.error_dx);
    w.error_dx.conservativeResize(n);
  }
  // A matrix that cannot filter (not finite) leaves the estimate as it is: larger, never smaller.
  return local_error_->measure(w.q, all_finite(w.error_dx) ? w.error_dx : w.error, *field_predictor_);
}

void GeneralizedAlpha::Impl::keep_step_start() {  // into the kept vectors: no allocation once their sizes are set
  IntegratorState& s = step_start_.state;
  step_start_.valid = true;
  s.time = t_;
  s.q = q_;
  s.v = v_;
  s.qdd = qdd_;
  s.a = a_;
  s.lambda = lambda_;
  s.nu = nu_;
  step_start_.a_before = a_before_;
  step_start_.h_before = h_before_;
}

void GeneralizedAlpha::Impl::restore_step_start() {
  if (!step_start_.valid) return;
  load(step_start_.state);
  a_before_ = step_start_.a_before;
  h_before_ = step_start_.h_before;
  step_start_.valid = false;
}

void GeneralizedAlpha::Impl::load(const IntegratorState& s) {
  t_ = s.time;
  q_ = s.q;
  v_ = s.v;
  qdd_ = s.qdd;
  a_ = s.a;
  lambda_ = s.lambda;
  nu_ = s.nu;
}

double GeneralizedAlpha::Impl::min_step() const {
  return options_.min_step > 0.0 ? options_.min_step : options_.step / kDefaultSplits;
}

// From t_ to t1 = t_ + h: as 2^pieces steps, and a step that fails as two halves, recursively, while a half is at least
// min_step; `depth` counts the halvings so far, `deepest` the most any step that was accepted needed.
void GeneralizedAlpha::Impl::cover(double h, double t1, int pieces, int depth, int& deepest) {
  const bool can_split = 0.5 * h >= min_step() * (1.0 - kStepToSlack);
  if (pieces > 0 && can_split) {
    const double mid = t_ + 0.5 * h;
    cover(mid - t_, mid, pieces - 1, depth + 1, deepest);
    cover(t1 - t_, t1, pieces - 1, depth + 1, deepest);
    return;
  }
  std::string failure;
  if (attempt_step(h, t1, failure)) {
    deepest = std::max(deepest, depth);
    if (depth > 0) smallest_step_ = std::min(smallest_step_, h);
    return;
  }
  if (!can_split) {
    std::ostringstream why;
    why << failure << " (a step of h = " << h << " s from t = " << t_ << " s";
    if (depth > 0) why << ", taken in halves down to min_step = " << min_step() << " s";
    else why << "; its halves would be below min_step = " << min_step() << " s";
    why << ")";
    throw StepFailure(why.str());
  }
  ++retried_steps_;
  if (!step_start_.valid) keep_step_start();  // nothing of this step was accepted yet
  const double mid = t_ + 0.5 * h;
  cover(mid - t_, mid, 0, depth + 1, deepest);
  cover(t1 - t_, t1, 0, depth + 1, deepest);
}

bool GeneralizedAlpha::Impl::attempt_step(double h, double t1, std::string& failure) {
  const Eigen::Index n = q_.size(), m = lambda_.size();
  // β' and γ' of the solver's matrix are those of the step it was built for; a step size changed by more than
  // kSameStep rebuilds it (step_to, a failed step's halves, error control), a kept one is a modified Newton matrix
  // (reuse_newton_matrix).
  if (std::abs(h - solver_step_) > kSameStep * solver_step_) build_solver(h);
  const StepFrame f{h, t1, (1.0 - alpha_m_) / (beta_ * h * h * (1.0 - alpha_f_)), gamma_ / (beta_ * h),
                    options_.constraints == ConstraintForm::stabilized_index2 && m > 0};
  // A Newton matrix kept from earlier iterations and steps (modified Newton) is refreshed when the corrections
  // stop shrinking fast (ratio > 1/4); a step that does not converge with a kept matrix is retried with a fresh one.
  bool fresh_this_step = false, coupled_this_step = false;
  if (fresh_starts_ > 0) {
    refresh_ = true;
    --fresh_starts_;
  }
  const bool kept_at_start = !refresh_ && options_.reuse_newton_matrix;  // a trial of the kept matrix
  for (int attempt = 0;; ++attempt) {
    predict(f);
    // The world's extent [m]: joints and springs compare positions of this size, so their residuals round at ε times
    // it, wherever the body is (a pendulum pivoted 100 m from the origin).
    double extent = ground_extent_;
    for (int b = 0; b < system_.body_count(); ++b) extent = std::max(extent, q_.segment<3>(system_.offset(b)).norm());
    if (iterate(f, extent, fresh_this_step, failure)) {
      if (all_finite(work_.q) && all_finite(work_.v) && all_finite(work_.qdd)) break;
      failure = "t = " + std::to_string(t1) + " s: the step converged to a non-finite state";
    }
    // A step that failed is tried again from its predictor (in the stabilised form moved by the last step's ν along the
    // Jacobian at the last step, which a fresh matrix then turns to its own; the failed iterate's Jacobian may not be
    // finite): with a fresh matrix if its matrix was kept, then (stabilised form) with the coupled step; then advance
    // takes it in halves.
    if (f.stabilized) system_.sparse_constraint_jacobian(t_, q_, work_.jacobian);
    if (attempt == 0 && !fresh_this_step) {  // the kept matrix was too old: once more with a fresh one
      refresh_ = true;
      continue;
    }
    if (f.stabilized && !couple_) {  // (couple_, not coupled_: an attempt may fail before its matrix is built)
      // A fresh matrix did not converge with the alternating step: once more with the coupled one, which then serves
      // the next kCoupledSteps steps, twice as many each time it is needed again (stabilized_coupling.hpp; slower to
      // build, so not used before it is needed).
      couple_ = refresh_ = coupled_this_step = true;
      if (!coupled_warned_) {
        coupled_warned_ = true;
        const std::string cost = sparse_core_ != nullptr ? "one sparse factorization of n + 2m unknowns" : "m solves";
        warnings_.push_back("t = " + std::to_string(t1) + " s: Newton did not converge with the stabilised index-2 "
                            "form's alternating step; such a step is taken with its coupled step, which costs " + cost +
                            " per Newton matrix (n = " + std::to_string(n) + " coordinates, m = " + std::to_string(m) +
                            " constraint rows), and so are the " + std::to_string(kCoupledSteps) + " steps after it "
                            "(twice as many each time it is needed again)");
      }
      continue;
    }
    if (failure.empty()) {
      Eigen::Index worst = 0;
      const Eigen::VectorXd now = system_.constraints(t1, work_.q);
      if (m > 0) now.cwiseAbs().maxCoeff(&worst);
      std::ostringstream why;
      why << "t = " << t1 << " s: Newton did not converge in " << options_.max_iterations
          << " iterations (largest constraint residual " << (m > 0 ? now.cwiseAbs().maxCoeff() : 0.0) << " in "
          << (m > 0 ? system_.constraint_name(worst) : std::string("none")) << ")" << last_state_diagnosis();
      failure = why.str();
    }
    refresh_ = true;  // the matrix of a failed iterate is not kept
    // The coupled step did not help either (tried now, or on since it rescued an earlier step): the halves start with
    // the alternating step again (a bracket pendulum's coupled step at 16 ms failed down to 0.25 ms pieces, where the
    // alternating one converges), each with the coupled step as its own retry.
    if (couple_ && !options_.coupled_from_start) {
      couple_ = false;
      coupled_steps_left_ = 0;
    }
    return false;
  }
  if (coupled_this_step) {  // it rescued this step: it serves the next ones too
    coupled_backoff_ = std::min(coupled_backoff_ > 0 ? 2 * coupled_backoff_ : kCoupledSteps, kLongestCoupling);
    coupled_steps_left_ = coupled_backoff_;
  }
  accept(f);
  // A kept matrix slowly goes stale as the bodies rotate away from where it was built: steps then need a third
  // or fourth iteration. Once such extra iterations add up to about the cost of building a new matrix (a build is
  // ~10 iterations' work: the elastic tangent and ~20 core products against 2-3 per iteration), rebuild it.
  if (kept_at_start) {
    fresh_start_backoff_ = fresh_this_step ? std::min(2 * fresh_start_backoff_ + 1, kLongestFreshStarts) : 0;
    fresh_starts_ = fresh_start_backoff_;
  }
  if (!fresh_this_step) extra_iterations_ += std::max(0, iterations_ - 2);  // a fresh matrix is not stale
  if (extra_iterations_ >= kExtraIterationsPerRebuild) refresh_ = true;
  // The coupled step's turn ends (the scene asked for it throughout: never).
  if (couple_ && !options_.coupled_from_start && !coupled_this_step && --coupled_steps_left_ <= 0) {
    couple_ = false;
    refresh_ = true;
  }
  total_iterations_ += iterations_;
  return true;
}

// The converged iterate becomes the state, after the checks of the model's validity.
void GeneralizedAlpha::Impl::accept(const StepFrame& f) {
  Iterate& w = work_;
  check_deformation(f.t1, w.q);
  check_spin(f.t1, w.q, w.v);
  w.a = (alpha_f_ * qdd_ - alpha_m_ * a_ + (1.0 - alpha_f_) * w.qdd) / (1.0 - alpha_m_);
  if (local_error_) step_error_ = estimate_step_error(f);
  q_ = w.q;
  v_ = w.v;
  qdd_ = w.qdd;
  a_ = w.a;
  lambda_ = f.beta_prime * w.mu;
  if (f.stabilized) nu_ = w.nu;
  t_ = f.t1;
}

}  // namespace flexbody::runtime
