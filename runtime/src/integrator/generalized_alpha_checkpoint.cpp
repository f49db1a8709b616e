// GeneralizedAlpha: save() and restore(), a run's continuation bit for bit (a scene's checkpoint). Besides
// the state, what the next steps depend on is the modified Newton matrix kept from an earlier iterate: restore()
// rebuilds it there, from the inputs build_newton_matrix recorded, with the sparse factorization's pivot history as
// it was before that build (ReducedSolver::restore_history).
#include "generalized_alpha_impl.hpp"

#include "local_error.hpp"
#include "newton_solvers.hpp"
#include "step_controller.hpp"

#include "flexbody/format/checkpoint_file.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace flexbody::runtime {
namespace {

using Entries = std::map<std::string, std::vector<double>>;

std::vector<double> values_of(const Eigen::VectorXd& x) { return {x.data(), x.data() + x.size()}; }

// The entry `name`, of `size` values (any size when size < 0).
const std::vector<double>& entry(const Entries& in, const std::string& name, long size = -1) {
  const auto found = in.find(name);
  if (found == in.end()) throw std::invalid_argument("checkpoint: missing entry " + name);
  if (size >= 0 && found->second.size() != static_cast<std::size_t>(size))
    throw std::invalid_argument("checkpoint: " + name + " has " + std::to_string(found->second.size()) +
                                " values, this scene " + std::to_string(size));
  return found->second;
}

Eigen::VectorXd vector_of(const Entries& in, const std::string& name, long size = -1) {
  const std::vector<double>& v = entry(in, name, size);
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

// The layout of "integrator.counts" (all exact integers or flags) and "integrator.times".
enum Count { kSteps, kRefresh, kExtra, kFreshStarts, kBackoff, kCouple, kCoupled, kIterations, kTotalIterations,
             kFactorizations, kBuilt, kBuildCouple, kBuildIterations, kCoordinates, kRows, kCountSize };
enum Time { kTime, kStart, kSolverStep, kBuildTime, kBuildStep, kStep, kRho, kTimeSize };

}  // namespace

void GeneralizedAlpha::Impl::save(format::CheckpointData& out) const {
  Entries& e = out.numbers;
  std::vector<double> counts(kCountSize), times(kTimeSize);
  counts[kSteps] = static_cast<double>(steps_);
  counts[kRefresh] = refresh_;
  counts[kExtra] = extra_iterations_;
  counts[kFreshStarts] = fresh_starts_;
  counts[kBackoff] = fresh_start_backoff_;
  counts[kCouple] = couple_;
  counts[kCoupled] = coupled_;
  counts[kIterations] = iterations_;
  counts[kTotalIterations] = static_cast<double>(total_iterations_);
  counts[kFactorizations] = static_cast<double>(factorizations_);
  counts[kBuilt] = built_at_.valid;
  counts[kBuildCouple] = built_at_.couple;
  counts[kBuildIterations] = built_at_.iterations;
  counts[kCoordinates] = static_cast<double>(q_.size());
  counts[kRows] = static_cast<double>(lambda_.size());
  times[kTime] = t_;
  times[kStart] = t0_;
  times[kSolverStep] = solver_step_;
  times[kBuildTime] = built_at_.t1;
  times[kBuildStep] = built_at_.h;
  times[kStep] = options_.step;
  times[kRho] = options_.rho_infinity;
  e["integrator.counts"] = counts;
  // The halving of failed steps and the coupled step's turn: what the next step starts with.
  e["integrator.retries"] = {static_cast<double>(split_), static_cast<double>(retried_steps_),
                             std::isfinite(smallest_step_) ? smallest_step_ : 0.0,  // 0: no step yet
                             static_cast<double>(coupled_steps_left_), static_cast<double>(coupled_backoff_),
                             coupled_warned_ ? 1.0 : 0.0, static_cast<double>(step_iterations_)};
  e["integrator.times"] = times;
  if (controller_) {  // error control: the controller's state, the last step's estimate, the largest step, the plan
    std::vector<double> control = controller_->state();
    control.insert(control.end(), {step_error_, largest_step_, tolerance_warned_ ? 1.0 : 0.0, plan_stop_, plan_size_,
                                   static_cast<double>(plan_growth_)});
    e["integrator.control"] = control;
    e["integrator.control.counted"] = local_error_->state();
    std::vector<double> before{h_before_};
    if (h_before_ > 0.0) before.insert(before.end(), a_before_.data(), a_before_.data() + a_before_.size());
    e["integrator.control.before"] = before;
  }
  e["integrator.q"] = values_of(q_);
  e["integrator.v"] = values_of(v_);
  e["integrator.qdd"] = values_of(qdd_);
  e["integrator.a"] = values_of(a_);
  e["integrator.lambda"] = values_of(lambda_);
  e["integrator.nu"] = values_of(nu_);
  e["integrator.spin_warned"].assign(spin_warned_.begin(), spin_warned_.end());
  if (built_at_.valid) {
    e["integrator.build.q"] = values_of(built_at_.q);
    e["integrator.build.shift"] = values_of(built_at_.shift);
    e["integrator.build.nu"] = values_of(built_at_.nu);
    e["integrator.build.v"] = values_of(built_at_.v);
    e["integrator.build.qdd"] = values_of(built_at_.qdd);
    e["integrator.build.mu"] = values_of(built_at_.mu);
  }
  solver_->save_history(e, "integrator.solver.");
  std::string warnings;
  for (const std::string& w : warnings_) warnings += w + '\n';
  out.texts["integrator.warnings"] = warnings;
}

void GeneralizedAlpha::Impl::restore(const format::CheckpointData& in) {
  const Entries& e = in.numbers;
  const std::vector<double>& counts = entry(e, "integrator.counts", kCountSize);
  const std::vector<double>& times = entry(e, "integrator.times", kTimeSize);
  const Eigen::Index n = q_.size(), m = lambda_.size();
  if (counts[kCoordinates] != static_cast<double>(n) || counts[kRows] != static_cast<double>(m))
    throw std::invalid_argument("checkpoint: its system has " + std::to_string(static_cast<long>(counts[kCoordinates])) +
                                " coordinates and " + std::to_string(static_cast<long>(counts[kRows])) +
                                " constraint rows, this one " + std::to_string(n) + " and " + std::to_string(m));
  if (times[kStep] != options_.step || times[kRho] != options_.rho_infinity) {
    std::ostringstream why;
    why << "checkpoint: written with step " << times[kStep] << " s and rho_inf " << times[kRho] << ", this run has "
        << options_.step << " s and " << options_.rho_infinity;
    throw std::invalid_argument(why.str());
  }
  IntegratorState state;
  state.time = times[kTime];
  state.q = vector_of(e, "integrator.q", n);
  state.v = vector_of(e, "integrator.v", n);
  state.qdd = vector_of(e, "integrator.qdd", n);
  state.a = vector_of(e, "integrator.a", n);
  state.lambda = vector_of(e, "integrator.lambda", m);
  state.nu = vector_of(e, "integrator.nu");
  set_state(state);  // checks the sizes and values
  const std::vector<double>& warned = entry(e, "integrator.spin_warned", static_cast<long>(spin_warned_.size()));
  spin_warned_.assign(warned.begin(), warned.end());
  const auto warnings = in.texts.find("integrator.warnings");
  if (warnings == in.texts.end()) throw std::invalid_argument("checkpoint: missing entry integrator.warnings");
  warnings_.clear();
  std::istringstream lines(warnings->second);
  for (std::string line; std::getline(lines, line);) warnings_.push_back(line);
  // The solver of the step size it was built for (step_to's last step may have left another), with the sparse
  // factorization's history as it was after the last build: that build, repeated, then ends as it did.
  build_solver(times[kSolverStep]);
  solver_->restore_history(e, "integrator.solver.");
  couple_ = counts[kCouple] != 0.0;
  coupled_ = counts[kCoupled] != 0.0;
  if (counts[kBuilt] != 0.0) {
    built_at_.valid = true;
    built_at_.t1 = times[kBuildTime];
    built_at_.h = times[kBuildStep];
    built_at_.couple = counts[kBuildCouple] != 0.0;
    built_at_.iterations = static_cast<int>(counts[kBuildIterations]);
    Iterate& w = work_;
    w.q = vector_of(e, "integrator.build.q", n);
    w.shift = vector_of(e, "integrator.build.shift");
    w.nu = vector_of(e, "integrator.build.nu");
    w.v = vector_of(e, "integrator.build.v", n);
    w.qdd = vector_of(e, "integrator.build.qdd", n);
    w.mu = vector_of(e, "integrator.build.mu", m);
    const StepFrame f{built_at_.h, built_at_.t1, (1.0 - alpha_m_) / (beta_ * built_at_.h * built_at_.h * (1.0 - alpha_f_)),
                      gamma_ / (beta_ * built_at_.h), options_.constraints == ConstraintForm::stabilized_index2 && m > 0};
    if (f.stabilized && (w.shift.size() != n || w.nu.size() != m))
      throw std::invalid_argument("checkpoint: integrator.build.shift or integrator.build.nu has the wrong size");
    const bool couple = couple_;
    couple_ = built_at_.couple;
    iterations_ = built_at_.iterations;
    bool evaluated = false;
    std::string failure;
    try {
      (void)build_newton_matrix(f, evaluated, failure);  // as it went then, a failure included (then refresh_ is set)
    } catch (const StepFailure&) {
    }
    couple_ = couple;
  }
  solver_->end_replay();  // a saved build that failed before its factorization leaves the replay unused
  steps_ = static_cast<long>(counts[kSteps]);
  t0_ = times[kStart];
  t_ = times[kTime];
  refresh_ = counts[kRefresh] != 0.0;
  coupled_ = counts[kCoupled] != 0.0;
  extra_iterations_ = static_cast<int>(counts[kExtra]);
  fresh_starts_ = static_cast<int>(counts[kFreshStarts]);
  fresh_start_backoff_ = static_cast<int>(counts[kBackoff]);
  iterations_ = static_cast<int>(counts[kIterations]);
  total_iterations_ = static_cast<long>(counts[kTotalIterations]);
  factorizations_ = static_cast<long>(counts[kFactorizations]);
  if (e.find("integrator.retries") == e.end())
    throw std::invalid_argument("checkpoint: written before failed steps were taken in halves (no entry "
                                "integrator.retries), which changed the steps: run the scene again from the start");
  const std::vector<double>& retries = entry(e, "integrator.retries", 7);
  split_ = static_cast<int>(retries[0]);
  retried_steps_ = static_cast<long>(retries[1]);
  smallest_step_ = retries[2] > 0.0 ? retries[2] : std::numeric_limits<double>::infinity();
  coupled_steps_left_ = static_cast<long>(retries[3]);
  coupled_backoff_ = static_cast<long>(retries[4]);
  coupled_warned_ = retries[5] != 0.0;
  step_iterations_ = static_cast<int>(retries[6]);
  const bool controlled = e.find("integrator.control") != e.end();
  if (controlled != (controller_ != nullptr))
    throw std::invalid_argument(controlled ? "checkpoint: written by a run under error control (integrator.control), "
                                             "this one takes fixed steps"
                                           : "checkpoint: written by a run with fixed steps (no integrator.control), "
                                             "this one is under error control");
  if (controller_) {
    const auto saved = e.find("integrator.control");
    if (saved->second.size() == detail::StepController::kStateSize + 3)
      throw std::invalid_argument("checkpoint: integrator.control has no step plan: it was written by an fbsim from "
                                  "before error control kept its step sizes, whose run this one cannot continue bit for "
                                  "bit; run from the start");
    const std::vector<double>& control =
        entry(e, "integrator.control", static_cast<long>(detail::StepController::kStateSize + 6));
    controller_->restore({control.begin(), control.begin() + detail::StepController::kStateSize});
    step_error_ = control[detail::StepController::kStateSize];
    largest_step_ = control[detail::StepController::kStateSize + 1];
    tolerance_warned_ = control[detail::StepController::kStateSize + 2] != 0.0;
    const double* plan = control.data() + detail::StepController::kStateSize + 3;  // stop, size, growth count
    if (!std::isfinite(plan[0]) || !(plan[1] >= 0.0 && std::isfinite(plan[1])) || !(plan[2] >= 0.0 && plan[2] <= 1e9))
      throw std::invalid_argument("checkpoint: integrator.control's step plan is malformed");
    plan_stop_ = plan[0];
    plan_size_ = plan[1];
    plan_growth_ = static_cast<int>(plan[2]);
    local_error_->restore(entry(e, "integrator.control.counted"));
    const std::vector<double>& before = entry(e, "integrator.control.before");
    h_before_ = before.empty() ? 0.0 : before[0];
    if (!(h_before_ >= 0.0) || before.size() != (h_before_ > 0.0 ? static_cast<std::size_t>(n) + 1 : 1))
      throw std::invalid_argument("checkpoint: integrator.control.before is malformed");
    if (h_before_ > 0.0) a_before_ = Eigen::Map<const Eigen::VectorXd>(before.data() + 1, n);
  }
}

}  // namespace flexbody::runtime
