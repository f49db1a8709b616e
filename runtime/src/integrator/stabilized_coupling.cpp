#include "stabilized_coupling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace flexbody::runtime::detail {

Eigen::SparseMatrix<double> constraint_rate(const System& system, double t, const Eigen::VectorXd& q,
                                            const Eigen::VectorXd& v, const Eigen::VectorXd& scales, double h,
                                            double gamma_prime) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  // Central differences, the step ∛ε over the fastest relative rate of a coordinate (|v_i| / (|q_i| + scale_i)) or
  // over 1/h, whichever is faster. Z only sets the convergence rate.
  double fastest = 1.0 / h;
  for (Eigen::Index i = 0; i < q.size(); ++i) fastest = std::max(fastest, std::abs(v(i)) / (std::abs(q(i)) + scales(i)));
  // t ± s exact: far from t = 0 the rounding of t + s would change the step of the time part (a driven joint's).
  const double guess = std::cbrt(eps) / fastest, exact = (t + guess) - t;
  const double s = exact > 0.0 ? exact : guess;
  Eigen::SparseMatrix<double> ahead, behind;  // one pattern: the difference is entrywise
  system.sparse_constraint_jacobian(t + s, q + s * v, ahead);
  system.sparse_constraint_jacobian(t - s, q - s * v, behind);
  return (ahead - behind) * (1.0 / (2.0 * s * gamma_prime));
}

bool StabilizedCoupling::build(const System& system, NewtonSolver& solver, double t, const Eigen::VectorXd& q,
                               const Eigen::VectorXd& v, const Eigen::VectorXd& qdd, const Eigen::VectorXd& mu,
                               const Eigen::MatrixXd& jacobian, const Eigen::MatrixXd& direction,
                               const Eigen::VectorXd& residual, const Eigen::VectorXd& scales, double beta_prime,
                               double gamma_prime, double h) {
  const Eigen::Index n = q.size(), m = jacobian.rows();
  constexpr double eps = std::numeric_limits<double>::epsilon();
  rate_ = Eigen::MatrixXd(constraint_rate(system, t, q, v, scales, h, gamma_prime));
  // G P, column by column: forward differences of r = R/β' + Jᵀ μ along each column of P, the step √ε in the
  // coordinate it moves most relative to its size.
  Eigen::MatrixXd rhs_dynamic(n, m), rhs_rows = jacobian * direction;
  Eigen::VectorXd moved(n), at_moved(n);
  for (Eigen::Index k = 0; k < m; ++k) {
    double reach = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) reach = std::max(reach, std::abs(direction(i, k)) / (std::abs(q(i)) + scales(i)));
    if (reach == 0.0) {
      rhs_dynamic.col(k).setZero();
      continue;
    }
    const double step = std::sqrt(eps) / reach;
    moved = q + step * direction.col(k);
    system.dynamic_residual(t, moved, v, qdd, at_moved);
    at_moved *= 1.0 / beta_prime;
    at_moved += system.constraint_jacobian_transpose_product(t, moved, mu);
    rhs_dynamic.col(k) = (at_moved - residual) / step;
  }
  coupling_.resize(n + m, m);
  Eigen::VectorXd column(n + m);
  for (Eigen::Index k = 0; k < m; ++k) {
    solver.solve(q, rhs_dynamic.col(k), rhs_rows.col(k), column);
    coupling_.col(k) = column;
  }
  const Eigen::MatrixXd projected = rhs_rows - rate_ * (coupling_.topRows(n) + direction);
  projection_.compute(projected);
  rhs_.resize(m);
  // Dependent rows are refused before (Φ_q W Φ_qᵀ); the rows' units differ (m, rad, kg^½ m), so a condition
  // estimate of this matrix says little, and a near-singular one shows as a correction that does not converge.
  return coupling_.allFinite() && rate_.allFinite() && projected.allFinite();
}

void StabilizedCoupling::complete(Eigen::VectorXd& dx, const Eigen::VectorXd& phi, const Eigen::VectorXd& velocity_rows,
                                  Eigen::VectorXd& nu_step) {
  const Eigen::Index n = rate_.cols();
  rhs_ = velocity_rows - phi;
  rhs_.noalias() += rate_ * dx.head(n);
  nu_step = projection_.solve(rhs_);
  dx.noalias() += coupling_ * nu_step;
}

}  // namespace flexbody::runtime::detail
