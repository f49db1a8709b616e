#include "local_error.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace flexbody::runtime::detail {

LocalError::LocalError(const System& system, const Eigen::VectorXd& reach, double coefficient,
                       const FieldPredictor& splitter)
    : coefficient_(coefficient), reach_(reach), weight_(reach.cwiseInverse()),
      field_frequencies_(splitter.frequencies()), fields_counted_(field_frequencies_.size(), 0) {
  for (int b = 0; b < system.body_count(); ++b) {
    const BodyModel& model = system.model(b);
    const Eigen::Index o = system.offset(b), n = model.coordinate_count();
    if (model.sparse)
      throw std::invalid_argument("generalized-alpha: error control measures a flexible body's deformation in the "
                                  "vibrations its step resolves, and body '" + system.body_name(b) + "' (the "
                                  "full-order model) has no modal split for that: give it a fixed step");
    if (model.floating()) {
      const FfrfModel& f = *model.floating_frame;
      Modes m{o + 7, Eigen::VectorXd(f.modes)};
      for (Eigen::Index k = 0; k < f.modes; ++k) m.omega2(k) = f.modal_stiffness(k, k) / f.modal_mass(k, k);
      modes_.push_back(std::move(m));
    } else if (!model.rigid() && splitter.splits(o)) {
      // Its fields are measured in their resolved components (FieldPredictor::displacement); a GCMS body the
      // predictor could not split is measured in every field.
      weight_.segment(o + 12, n - 12).setZero();
    }
  }
}

bool LocalError::counts(double omega2, double h, bool counted, bool first) {
  const double omega_h = std::sqrt(std::max(omega2, 0.0)) * h;
  if (first) return omega_h <= 1.0;
  return counted ? omega_h <= 2.0 : omega_h < 0.5;
}

void LocalError::set_step(double h) {
  for (const Modes& m : modes_)
    for (Eigen::Index k = 0; k < m.omega2.size(); ++k) {
      double& w = weight_(m.first + k);
      w = counts(m.omega2(k), h, w != 0.0, !stepped_) ? 1.0 / reach_(m.first + k) : 0.0;
    }
  for (std::size_t b = 0; b < field_frequencies_.size(); ++b) {  // ascending: the counted ones are the slowest
    const Eigen::VectorXd& omega2 = *field_frequencies_[b];
    Eigen::Index& counted = fields_counted_[b];
    Eigen::Index next = 0;
    while (next < omega2.size() && counts(omega2(next), h, next < counted, !stepped_)) ++next;
    counted = next;
  }
  stepped_ = true;
}

std::vector<double> LocalError::state() const {
  std::vector<double> out;
  for (const Modes& m : modes_)
    for (Eigen::Index k = 0; k < m.omega2.size(); ++k) out.push_back(weight_(m.first + k) != 0.0 ? 1.0 : 0.0);
  for (const Eigen::Index counted : fields_counted_) out.push_back(static_cast<double>(counted));
  return out;
}

void LocalError::restore(const std::vector<double>& state) {
  std::size_t expected = fields_counted_.size();
  for (const Modes& m : modes_) expected += static_cast<std::size_t>(m.omega2.size());
  if (state.size() != expected)
    throw std::invalid_argument("checkpoint: integrator.control.counted has " + std::to_string(state.size()) +
                                " entries, this system's error control " + std::to_string(expected));
  std::size_t i = 0;
  for (const Modes& m : modes_)
    for (Eigen::Index k = 0; k < m.omega2.size(); ++k)
      weight_(m.first + k) = state[i++] != 0.0 ? 1.0 / reach_(m.first + k) : 0.0;
  for (std::size_t b = 0; b < fields_counted_.size(); ++b) {
    const double counted = state[i++];
    if (!(counted >= 0.0 && counted <= static_cast<double>(field_frequencies_[b]->size())))
      throw std::invalid_argument("checkpoint: integrator.control.counted is out of range");
    fields_counted_[b] = static_cast<Eigen::Index>(counted);
  }
  stepped_ = true;
}

void LocalError::estimate(const Eigen::VectorXd& a_from, const Eigen::VectorXd& a_to, double h, double span,
                          Eigen::VectorXd& out) const {
  out = (coefficient_ * h * h * h / span) * (a_to - a_from);
}

double LocalError::measure(const Eigen::VectorXd& q, const Eigen::VectorXd& e, FieldPredictor& fields) const {
  if (e.size() == 0) return 0.0;
  const double direct = e.cwiseProduct(weight_).cwiseAbs().maxCoeff();
  return std::max(direct, fields.displacement(q, e, reach_, fields_counted_));
}

}  // namespace flexbody::runtime::detail
