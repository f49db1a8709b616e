#include "flexbody/preprocess/generalized_fields.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace flexbody::preprocess {
namespace {

Eigen::MatrixXd mass_times(const SparseMatrix& scalar_mass_upper, const Eigen::MatrixXd& fields) {
  return scalar_mass_upper.selfadjointView<Eigen::Upper>() * fields;
}

}  // namespace

GeneralizedFields orthonormal_fields(const SparseMatrix& scalar_mass_upper, const Eigen::MatrixXd& upsilon,
                                     const GeneralizedFieldOptions& options) {
  const Eigen::Index n_n = scalar_mass_upper.rows();
  if (upsilon.rows() != n_n || upsilon.cols() % 3 != 0)
    throw std::logic_error("orthonormal_fields: upsilon must be n_n x 3 n_m");
  const Eigen::Index n_m = upsilon.cols() / 3;

  // Kept fields Q and M_s Q, filled column by column (at most 3 n_m).
  Eigen::MatrixXd q(n_n, 3 * n_m), mq(n_n, 3 * n_m);
  Eigen::Index kept = 0;
  GeneralizedFields result;
  result.relative_remainders.resize(3 * n_m);
  std::vector<int> source;
  for (Eigen::Index m = 0; m < n_m; ++m) {
    Eigen::MatrixXd v = upsilon.middleCols(3 * m, 3);
    Eigen::MatrixXd mv = mass_times(scalar_mass_upper, v);
    const double mode_norm = std::sqrt((v.array() * mv.array()).sum());  // ||psi_m||_M = 1 for normalised modes
    // Project the mode's three fields off the fields kept so far: twice (CGS2), which makes them
    // orthogonal to working precision even when they were nearly dependent.
    for (int pass = 0; pass < 2 && kept > 0; ++pass) {
      const Eigen::MatrixXd c = q.leftCols(kept).transpose() * mv;
      v.noalias() -= q.leftCols(kept) * c;
      mv.noalias() -= mq.leftCols(kept) * c;
    }
    // Then one by one within the mode.
    const Eigen::Index first_of_mode = kept;
    for (int k = 0; k < 3; ++k) {
      Eigen::VectorXd x = v.col(k), mx = mv.col(k);
      for (int pass = 0; pass < 2 && kept > first_of_mode; ++pass) {
        const Eigen::Index block = kept - first_of_mode;
        const Eigen::VectorXd c = q.middleCols(first_of_mode, block).transpose() * mx;
        x.noalias() -= q.middleCols(first_of_mode, block) * c;
        mx.noalias() -= mq.middleCols(first_of_mode, block) * c;
      }
      const double remainder = std::sqrt(std::max(x.dot(mx), 0.0));
      const double relative = mode_norm > 0.0 ? remainder / mode_norm : 0.0;
      result.relative_remainders(3 * m + k) = relative;
      if (!(relative >= options.drop_tolerance)) {
        ++result.dropped;
        continue;
      }
      q.col(kept) = x / remainder;
      mq.col(kept) = mx / remainder;
      source.push_back(static_cast<int>(m));
      ++kept;
    }
  }
  result.upsilon = q.leftCols(kept);
  result.source_mode = Eigen::Map<const Eigen::VectorXi>(source.data(), static_cast<Eigen::Index>(source.size()));
  result.mode_coefficients = mq.leftCols(kept).transpose() * upsilon;
  return result;
}

double spectral_condition(const Eigen::MatrixXd& symmetric) {
  if (symmetric.size() == 0) return 1.0;
  const Eigen::VectorXd values = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(symmetric, Eigen::EigenvaluesOnly).eigenvalues();
  if (!(values(0) > 0.0)) return std::numeric_limits<double>::infinity();
  return values(values.size() - 1) / values(0);
}

double scaled_condition(const Eigen::MatrixXd& symmetric) {
  const Eigen::VectorXd diagonal = symmetric.diagonal();
  if (symmetric.size() == 0) return 1.0;
  if (!(diagonal.minCoeff() > 0.0)) return std::numeric_limits<double>::infinity();
  const Eigen::VectorXd scale = diagonal.cwiseSqrt().cwiseInverse();
  return spectral_condition(scale.asDiagonal() * symmetric * scale.asDiagonal());
}

}  // namespace flexbody::preprocess
