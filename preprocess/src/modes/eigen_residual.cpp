#include "flexbody/preprocess/eigen_residual.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace flexbody::preprocess {

double accepted_residual(double floor) { return std::max(kMinResidualBound, kResidualFloorFactor * floor); }

Eigen::Index worst_refused(const Eigen::Ref<const Eigen::VectorXd>& residuals,
                           const Eigen::Ref<const Eigen::VectorXd>& floors) {
  Eigen::Index worst = -1;
  double worst_excess = 0.0;
  for (Eigen::Index k = 0; k < residuals.size(); ++k) {
    const double excess = residuals(k) / accepted_residual(floors(k));
    if (excess <= 1.0) continue;
    if (worst < 0 || std::isnan(excess) || excess > worst_excess) {
      worst = k;
      worst_excess = excess;
    }
    if (std::isnan(excess)) break;
  }
  return worst;
}

std::string describe_refusal(double relative, double floor) {
  return fmt::format("relative residual {:.3g}, {:.3g} times its rounding floor {:.3g}; accepted up to max({:.0e}, "
                     "{:g} x floor) = {:.3g}", relative, relative / floor, floor, kMinResidualBound,
                     kResidualFloorFactor, accepted_residual(floor));
}

void apply_symmetric_with_magnitude(const SparseMatrix& upper, const Eigen::Ref<const Eigen::VectorXd>& x,
                                    Eigen::Ref<Eigen::VectorXd> y, Eigen::Ref<Eigen::VectorXd> z) {
  // Entry (i, j), i <= j, of the upper triangle adds a x_j to y_i and, off the diagonal, a x_i to y_j; the
  // magnitudes likewise with |a| and |x|.
  const Eigen::Index n = upper.cols();
  const std::int64_t* start = upper.outerIndexPtr();
  const std::int64_t* row = upper.innerIndexPtr();
  const double* value = upper.valuePtr();
  y.setZero();
  z.setZero();
  for (Eigen::Index j = 0; j < n; ++j) {
    const double xj = x(j), axj = std::abs(xj);
    double acc = 0.0, abs_acc = 0.0;
    const std::int64_t end = upper.isCompressed() ? start[j + 1] : start[j] + upper.innerNonZeroPtr()[j];
    for (std::int64_t k = start[j]; k < end; ++k) {
      const std::int64_t i = row[k];
      const double a = value[k], abs_a = std::abs(a);
      if (i == j) {
        acc += a * xj;
        abs_acc += abs_a * axj;
        continue;
      }
      y(i) += a * xj;
      z(i) += abs_a * axj;
      acc += a * x(i);
      abs_acc += abs_a * std::abs(x(i));
    }
    y(j) += acc;
    z(j) += abs_acc;
  }
}

void apply_vector_mass_with_magnitude(const SparseMatrix& scalar_mass_upper, const Eigen::Ref<const Eigen::VectorXd>& x,
                                      Eigen::Ref<Eigen::VectorXd> y, Eigen::Ref<Eigen::VectorXd> z) {
  const Eigen::Index n = scalar_mass_upper.cols();
  const std::int64_t* start = scalar_mass_upper.outerIndexPtr();
  const std::int64_t* row = scalar_mass_upper.innerIndexPtr();
  const double* value = scalar_mass_upper.valuePtr();
  y.setZero();
  z.setZero();
  for (Eigen::Index j = 0; j < n; ++j) {
    const Eigen::Vector3d xj = x.segment<3>(3 * j), axj = xj.cwiseAbs();
    Eigen::Vector3d acc = Eigen::Vector3d::Zero(), abs_acc = Eigen::Vector3d::Zero();
    const std::int64_t end =
        scalar_mass_upper.isCompressed() ? start[j + 1] : start[j] + scalar_mass_upper.innerNonZeroPtr()[j];
    for (std::int64_t k = start[j]; k < end; ++k) {
      const std::int64_t i = row[k];
      const double m = value[k], abs_m = std::abs(m);
      if (i == j) {
        acc += m * xj;
        abs_acc += abs_m * axj;
        continue;
      }
      y.segment<3>(3 * i) += m * xj;
      z.segment<3>(3 * i) += abs_m * axj;
      acc += m * x.segment<3>(3 * i);
      abs_acc += abs_m * x.segment<3>(3 * i).cwiseAbs();
    }
    y.segment<3>(3 * j) += acc;
    z.segment<3>(3 * j) += abs_acc;
  }
}

EigenResidual eigen_residual(const SparseMatrix& stiffness_upper, const SparseMatrix& scalar_mass_upper, double lambda,
                             const Eigen::Ref<const Eigen::VectorXd>& phi) {
  const Eigen::Index n = phi.size();
  Eigen::VectorXd kphi(n), abs_kphi(n), mphi(n), abs_mphi(n);
  apply_symmetric_with_magnitude(stiffness_upper, phi, kphi, abs_kphi);
  apply_vector_mass_with_magnitude(scalar_mass_upper, phi, mphi, abs_mphi);
  const double k_norm = kphi.norm();
  EigenResidual r;
  r.relative = (kphi - lambda * mphi).norm() / k_norm;
  r.floor = DBL_EPSILON * (abs_kphi.norm() + std::abs(lambda) * abs_mphi.norm()) / k_norm;
  return r;
}

}  // namespace flexbody::preprocess
