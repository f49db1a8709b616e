#include "flexbody/preprocess/generalized_fields.hpp"

#include "flexbody/preprocess/assembly.hpp"

#include "../linalg/blas_gemm.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace flexbody::preprocess {
GeneralizedFields orthonormal_fields(const SparseMatrix& scalar_mass_upper, const Eigen::MatrixXd& upsilon,
                                     const GeneralizedFieldOptions& options) {
  const Eigen::Index n_n = scalar_mass_upper.rows();
  if (upsilon.rows() != n_n || upsilon.cols() % 3 != 0)
    throw std::logic_error("orthonormal_fields: upsilon must be n_n x 3 n_m");
  const Eigen::Index n_m = upsilon.cols() / 3;
  // M_s with both triangles: about 230 products with one to three fields follow (4 s at 1M DOFs on the upper
  // triangle alone, one thread).
  const SparseMatrix mass_full = full_from_upper(scalar_mass_upper);
  auto mass_times = [&](const Eigen::MatrixXd& x) { return symmetric_product(mass_full, x); };

  // Kept fields Q and M_s Q, filled column by column (at most 3 n_m).
  Eigen::MatrixXd q(n_n, 3 * n_m), mq(n_n, 3 * n_m);
  Eigen::Index kept = 0;
  GeneralizedFields result;
  result.relative_remainders.resize(3 * n_m);
  std::vector<int> source;
  // Projects x off the columns [first, kept) of Q. M_s x is recomputed after every pass rather than
  // updated (M_s x - M_s Q c would carry the round-off of the removed part, eps ||x_0||, into the
  // remainder of a nearly dependent field). A second pass follows when the first removed more than half
  // of a column's norm ("twice is enough"); otherwise one pass is orthogonal to working precision.
  auto project = [&](Eigen::MatrixXd& x, Eigen::MatrixXd& mx, Eigen::Index first) {
    for (int pass = 0; pass < 2 && kept > first; ++pass) {
      const Eigen::RowVectorXd before = (x.array() * mx.array()).colwise().sum();
      const Eigen::MatrixXd c = q.middleCols(first, kept - first).transpose() * mx;
      x.noalias() -= q.middleCols(first, kept - first) * c;
      mx = mass_times(x);
      const Eigen::RowVectorXd after = (x.array() * mx.array()).colwise().sum();
      if ((after.array() >= 0.25 * before.array()).all()) break;  // squared norms: 0.25 = half the norm
    }
  };
  for (Eigen::Index m = 0; m < n_m; ++m) {
    Eigen::MatrixXd v = upsilon.middleCols(3 * m, 3);
    Eigen::MatrixXd mv = mass_times(v);
    const double mode_norm = std::sqrt((v.array() * mv.array()).sum());  // ||psi_m||_M = 1 for normalised modes
    project(v, mv, 0);  // the mode's three fields off every field kept so far, as one block
    const Eigen::Index first_of_mode = kept;
    for (int k = 0; k < 3; ++k) {  // then one by one within the mode
      Eigen::MatrixXd x = v.col(k), mx = mv.col(k);
      project(x, mx, first_of_mode);
      const double remainder = std::sqrt(std::max(x.col(0).dot(mx.col(0)), 0.0));
      const double relative = mode_norm > 0.0 ? remainder / mode_norm : 0.0;
      result.relative_remainders(3 * m + k) = relative;
      if (!(relative >= options.drop_tolerance)) {
        ++result.dropped;
        continue;
      }
      q.col(kept) = x.col(0) / remainder;
      mq.col(kept) = mx.col(0) / remainder;
      source.push_back(static_cast<int>(m));
      ++kept;
    }
  }
  result.upsilon = q.leftCols(kept);
  result.mass_upsilon = mq.leftCols(kept);
  result.source_mode = Eigen::Map<const Eigen::VectorXi>(source.data(), static_cast<Eigen::Index>(source.size()));
  result.mode_coefficients = blas::transposed_product(result.mass_upsilon, upsilon);
  return result;
}

double spectral_condition(const Eigen::MatrixXd& symmetric) {
  // A direct eigen solve of A finds λmin only to about eps λmax absolute, which is all of it when A's rows
  // carry different units: G of a 1 mm steel part has λmin/λmax ~ 1e-20 (second moments in kg m^2 next to
  // the fields' identity block), and the solve returns λmin <= 0 or noise. So A = S^-1 Â S^-1 is taken
  // apart by its Jacobi scaling (S = D^-1/2, D = diag A; Â has unit diagonal and no units): λmax(A) comes from A
  // itself (a largest eigenvalue is found to eps relative), λmin(A) = 1 / λmax(A^-1) with
  // A^-1 = S Â^-1 S = B Bᵀ, B = S V Λ^-1/2 from Â = V Λ Vᵀ, whose largest eigenvalue is again found to eps
  // relative. The result is accurate to about eps cond(Â), whatever the units or the part's size.
  if (symmetric.size() == 0) return 1.0;
  const double infinity = std::numeric_limits<double>::infinity();
  const Eigen::VectorXd diagonal = symmetric.diagonal();
  if (!(diagonal.minCoeff() > 0.0)) return infinity;
  const Eigen::VectorXd scale = diagonal.cwiseSqrt().cwiseInverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> scaled(scale.asDiagonal() * symmetric * scale.asDiagonal());
  if (scaled.info() != Eigen::Success || !(scaled.eigenvalues()(0) > 0.0)) return infinity;
  const Eigen::MatrixXd b =
      scale.asDiagonal() * scaled.eigenvectors() * scaled.eigenvalues().cwiseSqrt().cwiseInverse().asDiagonal();
  const double inverse_max =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(b.transpose() * b, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  const double max = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(symmetric, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  return max * inverse_max;
}

double scaled_condition(const Eigen::MatrixXd& symmetric) {
  const Eigen::VectorXd diagonal = symmetric.diagonal();
  if (symmetric.size() == 0) return 1.0;
  if (!(diagonal.minCoeff() > 0.0)) return std::numeric_limits<double>::infinity();
  const Eigen::VectorXd scale = diagonal.cwiseSqrt().cwiseInverse();
  const Eigen::VectorXd values =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scale.asDiagonal() * symmetric * scale.asDiagonal(),
                                                     Eigen::EigenvaluesOnly)
          .eigenvalues();
  if (!(values(0) > 0.0)) return std::numeric_limits<double>::infinity();
  return values(values.size() - 1) / values(0);
}

}  // namespace flexbody::preprocess
