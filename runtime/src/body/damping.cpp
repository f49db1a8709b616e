#include "flexbody/runtime/damping.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace flexbody::runtime {

namespace {

void refuse_full_order(const BodyModel& model) {
  if (model.sparse) throw std::invalid_argument(model.source + ": the full-order reference body takes no damping");
}

}  // namespace

Eigen::MatrixXd modal_damping(const BodyModel& model, const Eigen::VectorXd& ratios) {
  refuse_full_order(model);
  if (ratios.size() != model.modes)
    throw std::invalid_argument(model.source + ": " + std::to_string(ratios.size()) + " modal damping ratios for " +
                                std::to_string(model.modes) + " modes");
  const Eigen::Index n = 3 * model.field_count();
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index m = 0; m < model.modes; ++m) {
    if (!(ratios(m) >= 0.0 && ratios(m) <= 1.0))
      throw std::invalid_argument(model.source + ": modal damping ratio of mode " + std::to_string(m + 1) +
                                  " must lie in [0, 1], got " + std::to_string(ratios(m)));
    Eigen::VectorXd c(n);
    for (Eigen::Index f = 0; f < model.field_count(); ++f) c.segment<3>(3 * f) = model.mode_coefficients.block<1, 3>(f, 3 * m).transpose();
    const double omega = 2.0 * std::numbers::pi * model.frequencies_hz(m);
    d += 2.0 * ratios(m) * omega * c * c.transpose();
  }
  return d;
}

Eigen::MatrixXd rayleigh_damping(const BodyModel& model, double alpha, double beta) {
  refuse_full_order(model);
  if (!(alpha >= 0.0) || !(beta >= 0.0) || !std::isfinite(alpha) || !std::isfinite(beta))
    throw std::invalid_argument(model.source + ": Rayleigh damping needs alpha, beta >= 0");
  const Eigen::Index n_f = model.field_count();
  Eigen::MatrixXd d = beta * model.stiffness;
  for (Eigen::Index f = 0; f < n_f; ++f)
    for (Eigen::Index g = 0; g < n_f; ++g) d.block<3, 3>(3 * f, 3 * g).diagonal().array() += alpha * model.mass_matrix(4 + f, 4 + g);
  return d;
}

}  // namespace flexbody::runtime
