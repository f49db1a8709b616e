#include "flexbody/runtime/generalized_alpha.hpp"

#include "newton_solvers.hpp"

#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

#include <cmath>
#include <limits>
#include <sstream>

namespace flexbody::runtime {
namespace {

// d/dt (Φ_q q̇ + Φ_t) at fixed q̇, by central differences along (q + s q̇, t + s): the acceleration-level
// right-hand side of the consistent initial accelerations (a directional derivative, accurate to ~1e-10).
Eigen::VectorXd constraint_curvature(const System& system, double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  const double s = 1e-6 / std::max(1.0, v.cwiseAbs().maxCoeff());
  auto phi_dot = [&](double shift) {
    const Eigen::VectorXd qs = q + shift * v;
    const double ts = t + shift, dt = 1e-6;
    const Eigen::VectorXd phi_t = (system.constraints(ts + dt, qs) - system.constraints(ts - dt, qs)) / (2 * dt);
    return Eigen::VectorXd(system.constraint_jacobian(ts, qs) * v + phi_t);
  };
  return (phi_dot(s) - phi_dot(-s)) / (2 * s);
}

// Whether every entry is finite, in one vectorized pass: a NaN or an infinity in any entry makes the sum NaN or
// infinite. (Eigen's allFinite() tests entry by entry; a sum of finite entries could only overflow near 1e308,
// which is no state to go on from either.)
bool all_finite(const Eigen::VectorXd& x) { return std::isfinite(x.sum()); }

}  // namespace

void GeneralizedAlpha::check_deformation(double t, const Eigen::VectorXd& q) const {
  if (!(options_.deformation_limit > 0.0)) return;
  for (int b = 0; b < system_.body_count(); ++b) {
    const BodyModel& model = system_.model(b);
    if (model.rigid()) continue;
    // ∫|ū|² dm = ξ̄ᵀ (G_ff ⊗ I3) ξ̄, and |ξ̄| = |ξ| for orthogonal A: the RMS displacement without rotating.
    const double squared = field_mass_norm_squared(model, q.segment(system_.offset(b) + 12, model.coordinate_count() - 12));
    const double rms = std::sqrt(std::max(squared, 0.0) / model.mass);
    const double size = body_sizes_[static_cast<std::size_t>(b)];
    if (rms > options_.deformation_limit * size) {
      std::ostringstream why;
      why << "t = " << t << " s: body '" << system_.body_name(b) << "' left the small-deformation range of its linear "
          << "model: RMS elastic displacement " << rms << " m = " << 100.0 * rms / size << " % of its size (limit "
          << 100.0 * options_.deformation_limit << " %). The improved GCMS has no geometric stiffening (FORMULATION.md "
          << "section 8): a spin above the first bending frequency, or a load beyond linear elasticity";
      throw StepFailure(why.str());
    }
  }
}

GeneralizedAlpha::GeneralizedAlpha(const System& system, const GeneralizedAlphaOptions& options, double t0)
    : system_(system), options_(options), t0_(t0), t_(t0) {
  const double rho = options.rho_infinity;
  if (!(rho >= 0.0 && rho <= 1.0)) throw std::invalid_argument("generalized-alpha: rho_inf must lie in [0, 1]");
  if (!(options.step > 0.0) || !std::isfinite(options.step))
    throw std::invalid_argument("generalized-alpha: the step must be positive");
  if (options.max_iterations < 1 || !(options.tolerance > 0.0) || !(options.deformation_limit >= 0.0))
    throw std::invalid_argument("generalized-alpha: max_iterations >= 1, tolerance > 0 and deformation_limit >= 0 "
                                "are required");
  alpha_m_ = (2.0 * rho - 1.0) / (rho + 1.0);
  alpha_f_ = rho / (rho + 1.0);
  gamma_ = 0.5 + alpha_f_ - alpha_m_;
  beta_ = 0.25 * (gamma_ + 0.5) * (gamma_ + 0.5);
  q_ = system.initial_coordinates();
  v_ = system.initial_velocities();
  for (int b = 0; b < system.body_count(); ++b) {  // bounding-box diagonals, for the deformation limit
    const format::RowMatrixX3d& nodes = system.model(b).nodes;
    body_sizes_.push_back(nodes.rows() ? (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).norm() : 0.0);
  }
  const Eigen::Index n = q_.size(), m = system.constraint_count();
  const Eigen::VectorXd phi = system.constraints(t_, q_);
  for (Eigen::Index k = 0; k < m; ++k)
    if (std::abs(phi(k)) > 1e-8)
      throw std::invalid_argument("initial state violates " + system.constraint_name(k) + " by " + std::to_string(phi(k)));
  // [M Φ_qᵀ; Φ_q 0], sparse: M is block diagonal and the full-order body's blocks have the mesh's sparsity.
  const Eigen::MatrixXd jac = system.constraint_jacobian(t_, q_);
  const Eigen::SparseMatrix<double> mass = system.sparse_mass_matrix();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(mass.nonZeros()));
  for (Eigen::Index k = 0; k < mass.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(mass, k); it; ++it) entries.emplace_back(it.row(), it.col(), it.value());
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      if (jac(i, j) != 0.0) {
        entries.emplace_back(n + i, j, jac(i, j));
        entries.emplace_back(j, n + i, jac(i, j));
      }
  Eigen::SparseMatrix<double> kkt(n + m, n + m);
  kkt.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  lu.compute(kkt);
  auto refuse = [&] {
    const Eigen::Index redundant = system.first_redundant_constraint(t_, q_);
    throw std::invalid_argument(redundant >= 0 ? system.constraint_name(redundant) + " is redundant: it repeats what "
                                                     "the constraints before it already impose"
                                               : std::string("initial accelerations: the matrix [M J^T; J 0] is singular"));
  };
  if (lu.info() != Eigen::Success) refuse();
  // Consistent velocities: the M-nearest v with Φ_q v + Φ_t = 0 (a driven joint that starts moving, or initial
  // velocities that fight a joint, would otherwise give a velocity jump and a spike in the multipliers).
  {
    const double dt = 1e-6;
    const Eigen::VectorXd phi_t = (system.constraints(t_ + dt, q_) - system.constraints(t_ - dt, q_)) / (2 * dt);
    if ((jac * v_ + phi_t).cwiseAbs().maxCoeff() > 1e-12 * std::max(1.0, v_.cwiseAbs().maxCoeff())) {
      Eigen::VectorXd rhs(n + m);
      rhs << mass * v_, -phi_t;
      const Eigen::VectorXd projected = lu.solve(rhs);
      if (!projected.allFinite() || (kkt * projected - rhs).norm() > 1e-8 * std::max(1.0, rhs.norm())) refuse();
      v_ = projected.head(n);
    }
  }
  Eigen::VectorXd rhs(n + m);
  rhs << system.forces(t_, q_, v_), -constraint_curvature(system, t_, q_, v_);
  const Eigen::VectorXd x = lu.solve(rhs);
  if (!x.allFinite() || (kkt * x - rhs).norm() > 1e-8 * std::max(1.0, rhs.norm())) refuse();
  qdd_ = x.head(n);
  lambda_ = x.tail(m);
  a_ = qdd_;
  const double beta_prime = (1.0 - alpha_m_) / (beta_ * options.step * options.step * (1.0 - alpha_f_));
  const double gamma_prime = gamma_ / (beta_ * options.step);
  if (options.newton_matrix == NewtonMatrix::dense)
    solver_ = std::make_unique<detail::DenseNewton>(system, beta_prime, gamma_prime);
  else
    solver_ = std::make_unique<detail::ConstantCoreNewton>(system, beta_prime, gamma_prime);
}

GeneralizedAlpha::~GeneralizedAlpha() = default;

void GeneralizedAlpha::step() {
  const double h = options_.step;
  const Eigen::Index n = q_.size(), m = lambda_.size();
  const double t1 = t0_ + static_cast<double>(steps_ + 1) * h;
  const double beta_prime = (1.0 - alpha_m_) / (beta_ * h * h * (1.0 - alpha_f_));
  const double gamma_prime = gamma_ / (beta_ * h);
  // The iterate, kept as members so that their storage is reused from step to step.
  Eigen::VectorXd &qdd = work_.qdd, &a = work_.a, &v = work_.v, &q = work_.q, &mu = work_.mu, &dx = work_.dx;
  Eigen::VectorXd& residual = work_.residual;  // the dynamic rows, scaled by 1/β'; the constraint rows are Φ
  // A Newton matrix kept from earlier iterations and steps (modified Newton) is refreshed when the corrections
  // stop shrinking fast (ratio > 1/4); a step that does not converge with a kept matrix is retried with a fresh one.
  bool fresh_this_step = false;
  for (int attempt = 0;; ++attempt) {
    // Predictor: q̈_{n+1} = q̈_n.
    qdd = qdd_;
    a = (alpha_f_ * qdd_ - alpha_m_ * a_ + (1.0 - alpha_f_) * qdd) / (1.0 - alpha_m_);
    v = v_ + h * (1.0 - gamma_) * a_ + h * gamma_ * a;
    q = q_ + h * v_ + h * h * (0.5 - beta_) * a_ + h * h * beta_ * a;
    mu = lambda_ / beta_prime;  // the scaled multipliers
    const double q_scale = 1.0 + q.cwiseAbs().maxCoeff();
    double previous_correction = std::numeric_limits<double>::infinity();
    bool converged = false;
    for (iterations_ = 1; iterations_ <= options_.max_iterations; ++iterations_) {
      const Eigen::VectorXd phi = system_.constraints(t1, q);
      const Eigen::VectorXd inertia = system_.mass_product(qdd);
      residual = (inertia - system_.forces(t1, q, v)) * (1.0 / beta_prime) +  // a product: a division per entry costs
                 system_.constraint_jacobian_transpose_product(t1, q, mu);   // more than the rest of this line
      if (refresh_ || !options_.reuse_newton_matrix) {
        solver_->factor(q, v, mu, system_.constraint_jacobian(t1, q));
        refresh_ = false;
        extra_iterations_ = 0;
        fresh_this_step = true;
        ++factorizations_;
      }
      solver_->solve(q, residual, phi, dx);
      if (!all_finite(dx)) {
        std::ostringstream why;
        Eigen::Index worst = 0;
        if (m > 0) phi.cwiseAbs().maxCoeff(&worst);
        why << "t = " << t1 << " s: the Newton matrix is singular or the state is not finite (largest constraint "
            << "residual in " << (m > 0 ? system_.constraint_name(worst) : std::string("none")) << ")";
        throw StepFailure(why.str());
      }
      q += dx.head(n);
      v += gamma_prime * dx.head(n);
      qdd += beta_prime * dx.head(n);
      mu += dx.tail(m);
      const double correction = dx.head(n).cwiseAbs().maxCoeff();
      const double force_scale = 1.0 + inertia.cwiseAbs().maxCoeff() / beta_prime;
      if (correction <= options_.tolerance * q_scale &&
          residual.cwiseAbs().maxCoeff() <= 1e3 * options_.tolerance * force_scale) {
        converged = true;
        break;
      }
      if (correction > 0.25 * previous_correction) refresh_ = true;
      previous_correction = correction;
    }
    if (converged) break;
    if (attempt == 0 && !fresh_this_step) {  // the kept matrix was too old: once more with a fresh one
      refresh_ = true;
      continue;
    }
    check_deformation(t1, q);  // a diverging linear model: say so rather than "did not converge"
    Eigen::Index worst = 0;
    const Eigen::VectorXd now = system_.constraints(t1, q);
    if (m > 0) now.cwiseAbs().maxCoeff(&worst);
    std::ostringstream why;
    why << "t = " << t1 << " s: Newton did not converge in " << options_.max_iterations
        << " iterations (largest constraint residual " << (m > 0 ? now.cwiseAbs().maxCoeff() : 0.0) << " in "
        << (m > 0 ? system_.constraint_name(worst) : std::string("none")) << ")";
    throw StepFailure(why.str());
  }
  if (!all_finite(q) || !all_finite(v) || !all_finite(qdd)) throw StepFailure("t = " + std::to_string(t1) + " s: non-finite state");
  check_deformation(t1, q);
  a = (alpha_f_ * qdd_ - alpha_m_ * a_ + (1.0 - alpha_f_) * qdd) / (1.0 - alpha_m_);
  q_ = q;
  v_ = v;
  qdd_ = qdd;
  a_ = a;
  lambda_ = beta_prime * mu;
  // A kept matrix slowly goes stale as the bodies rotate away from where it was built: steps then need a third
  // or fourth iteration. Once such extra iterations add up to about the cost of building a new matrix (a build is
  // ~10 iterations' work: the elastic tangent and ~20 core products against 2-3 per iteration), rebuild it.
  if (!fresh_this_step) extra_iterations_ += std::max(0, iterations_ - 2);  // a fresh matrix is not stale
  if (extra_iterations_ >= kExtraIterationsPerRebuild) refresh_ = true;
  t_ = t1;
  ++steps_;
  total_iterations_ += iterations_;
}

}  // namespace flexbody::runtime
