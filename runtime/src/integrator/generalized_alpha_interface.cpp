// The installed GeneralizedAlpha: each member forwards to its Impl (generalized_alpha_impl.hpp), so that the
// integrator's state and work storage stay out of the installed header.
#include "generalized_alpha_impl.hpp"

namespace flexbody::runtime {

GeneralizedAlpha::GeneralizedAlpha(const System& system, const GeneralizedAlphaOptions& options, double t0)
    : impl_(std::make_unique<Impl>(system, options, t0)) {}
GeneralizedAlpha::~GeneralizedAlpha() = default;

void GeneralizedAlpha::step() { impl_->step(); }
void GeneralizedAlpha::step_to(double t_end) { impl_->step_to(t_end); }
void GeneralizedAlpha::step_toward(double t_stop) { impl_->step_toward(t_stop); }
IntegratorState GeneralizedAlpha::state() const { return impl_->state(); }
void GeneralizedAlpha::set_state(const IntegratorState& state) { impl_->set_state(state); }
void GeneralizedAlpha::save(format::CheckpointData& out) const { impl_->save(out); }
void GeneralizedAlpha::restore(const format::CheckpointData& in) { impl_->restore(in); }

double GeneralizedAlpha::time() const { return impl_->t_; }
const Eigen::VectorXd& GeneralizedAlpha::coordinates() const { return impl_->q_; }
const Eigen::VectorXd& GeneralizedAlpha::velocities() const { return impl_->v_; }
const Eigen::VectorXd& GeneralizedAlpha::accelerations() const { return impl_->qdd_; }
const Eigen::VectorXd& GeneralizedAlpha::multipliers() const { return impl_->lambda_; }
int GeneralizedAlpha::last_iterations() const { return impl_->step_iterations_; }
long GeneralizedAlpha::total_iterations() const { return impl_->total_iterations_; }
long GeneralizedAlpha::factorizations() const { return impl_->factorizations_; }
long GeneralizedAlpha::retried_steps() const { return impl_->retried_steps_; }
double GeneralizedAlpha::smallest_step() const { return impl_->smallest_step_; }
double GeneralizedAlpha::largest_step() const { return impl_->largest_step_; }
long GeneralizedAlpha::rejected_steps() const { return impl_->rejected_steps(); }
long GeneralizedAlpha::steps_above_tolerance() const { return impl_->steps_above_tolerance(); }
double GeneralizedAlpha::step_error() const { return impl_->step_error_; }
double GeneralizedAlpha::next_step() const { return impl_->next_step(); }
double GeneralizedAlpha::min_step() const { return impl_->min_step(); }
bool GeneralizedAlpha::sparse() const { return impl_->sparse_; }
const std::vector<std::string>& GeneralizedAlpha::warnings() const { return impl_->warnings_; }

}  // namespace flexbody::runtime
