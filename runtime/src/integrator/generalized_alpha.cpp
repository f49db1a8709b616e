// GeneralizedAlpha: the consistent initial state, each coordinate's length scale, and the Newton solver; a step is
// in generalized_alpha_step.cpp, its Newton iteration in generalized_alpha_newton.cpp.
#include "generalized_alpha_impl.hpp"

#include "../body/body_measures.hpp"
#include "constraint_projection.hpp"
#include "field_predictor.hpp"
#include "local_error.hpp"
#include "newton_solvers.hpp"
#include "saddle_point.hpp"
#include "stabilized_coupling.hpp"
#include "step_controller.hpp"

#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace flexbody::runtime {
namespace {

// d/dt (Φ_q q̇ + Φ_t) at fixed q̇, by central differences along (q + s q̇, t + s): the acceleration-level
// right-hand side of the consistent initial accelerations (a directional derivative). The step is ∛ε over the fastest
// relative rate of a coordinate, |q̇_i| / (|q_i| + scale_i), or 1/h, as constraint_rate's (stabilized_coupling.cpp):
// truncation and rounding both ~ε^⅔ of the terms. (A fixed 1e-6 s differenced a 1 mm part spinning at 3.3e5 rad/s
// over 0.3 rad, and its initial accelerations were off by 40 %.)
Eigen::VectorXd constraint_curvature(const System& system, double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                     const Eigen::VectorXd& scales, double h) {
  double fastest = 1.0 / h;
  for (Eigen::Index i = 0; i < q.size(); ++i) fastest = std::max(fastest, std::abs(v(i)) / (std::abs(q(i)) + scales(i)));
  const double guess = std::cbrt(std::numeric_limits<double>::epsilon()) / fastest, exact = (t + guess) - t;
  const double s = exact > 0.0 ? exact : guess;  // t ± s exact, so that the time part's step is s
  auto phi_dot = [&](double shift) {
    const Eigen::VectorXd qs = q + shift * v;
    Eigen::SparseMatrix<double> jacobian;
    system.sparse_constraint_jacobian(t + shift, qs, jacobian);
    return Eigen::VectorXd(jacobian * v + system.constraint_time_derivative(t + shift, qs, h));
  };
  return (phi_dot(s) - phi_dot(-s)) / (2 * s);
}

// The initial velocities' correction by the rigid velocities alone is taken while its kinetic energy is at most this
// many times the M-nearest correction's over all velocities (GeneralizedAlpha's constructor). Measured: the beam driven
// at its rbe3 root in the scale test 20 times (the M-nearest one moved the root through the modes' rotation), the
// pinned beam of fast_spin_test 1.0; a deformed tumbling beam's Tisserand rows 4e31 times (rejected).
constexpr double kRigidCorrectionRatio = 100.0;

}  // namespace

GeneralizedAlpha::Impl::Impl(const System& system, const GeneralizedAlphaOptions& options, double t0)
    : system_(system), options_(options), t0_(t0), t_(t0), coupling_(std::make_unique<detail::StabilizedCoupling>()) {
  if (const std::optional<OptionProblem> problem = check_options(options))
    throw std::invalid_argument("generalized-alpha: " + problem->message);
  const double rho = options.rho_infinity;
  alpha_m_ = (2.0 * rho - 1.0) / (rho + 1.0);
  alpha_f_ = rho / (rho + 1.0);
  gamma_ = 0.5 + alpha_f_ - alpha_m_;
  beta_ = 0.25 * (gamma_ + 0.5) * (gamma_ + 0.5);
  q_ = system.initial_coordinates();
  v_ = system.initial_velocities();
  scales_.resize(q_.size());
  reach_.resize(q_.size());
  for (int b = 0; b < system.body_count(); ++b) {
    const Eigen::Index o = system.offset(b), n_b = system.model(b).coordinate_count();
    detail::coordinate_scales(system.model(b), scales_.segment(o, n_b));
    reach_.segment(o, n_b) = scales_.segment(o, n_b) / scales_(o);  // scale per metre: τ's scale is r
  }
  for (const Joint& j : system.joints()) {
    time_dependent_ = time_dependent_ || j.type == JointType::driven_revolute;
    for (const Marker* m : {&j.first, &j.second})
      if (m->body == kGround) ground_extent_ = std::max(ground_extent_, m->ground_point.norm());
  }
  squared_scales_ = scales_.array().square();
  for (int b = 0; b < system.body_count(); ++b) {  // W: divided by each body's m r² (see metric_)
    const Eigen::Index o = system.offset(b), n_b = system.model(b).coordinate_count();
    squared_scales_.segment(o, n_b) /= system.model(b).mass * scales_(o) * scales_(o);
  }
  if (!scales_.allFinite() || !(scales_.minCoeff() > 0.0))
    throw std::invalid_argument("generalized-alpha: a body has no length scale for Newton's stopping test (zero or "
                                "non-finite radius of gyration, or a field that displaces no node)");
  spin_warned_.assign(static_cast<std::size_t>(system.body_count()), 0);
  for (int b = 0; b < system.body_count(); ++b) prestress_gaps_.push_back(system.prestress_gap(b));
  for (int b = 0; b < system.body_count(); ++b) {  // for the deformation limit
    body_sizes_.push_back(detail::mesh_diagonal(system.model(b)));
    deformations_.emplace_back(system.model(b));
  }
  const Eigen::Index n = q_.size(), m = system.constraint_count();
  const Eigen::VectorXd phi = system.constraints(t_, q_);
  for (Eigen::Index k = 0; k < m; ++k)
    if (std::abs(phi(k)) > 1e-8)
      throw std::invalid_argument("initial state violates " + system.constraint_name(k) + " by " +
                                  std::to_string(phi(k)) +
                                  " (runtime::initial_assembly closes the joints' gaps; initial_assembly.hpp)");
  // [M Φ_qᵀ; Φ_q 0], sparse: M is block diagonal and the full-order body's blocks have the mesh's sparsity.
  Eigen::SparseMatrix<double> jac;
  system.sparse_constraint_jacobian(t_, q_, jac);
  const Eigen::SparseMatrix<double> mass = system.sparse_mass_matrix(q_);
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(mass.nonZeros() + 2 * jac.nonZeros()));
  for (Eigen::Index k = 0; k < mass.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(mass, k); it; ++it) entries.emplace_back(it.row(), it.col(), it.value());
  for (Eigen::Index k = 0; k < jac.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(jac, k); it; ++it)
      if (it.value() != 0.0) {
        entries.emplace_back(n + it.row(), it.col(), it.value());
        entries.emplace_back(it.col(), n + it.row(), it.value());
      }
  Eigen::SparseMatrix<double> kkt(n + m, n + m);  // for the residuals of the solves
  kkt.setFromTriplets(entries.begin(), entries.end());
  std::vector<bool> mesh_sized(static_cast<std::size_t>(n), false);  // the full-order bodies' fields (saddle_point.hpp)
  for (int b = 0; b < system.body_count(); ++b)
    if (system.model(b).sparse)
      for (Eigen::Index k = 12; k < system.model(b).coordinate_count(); ++k)
        mesh_sized[static_cast<std::size_t>(system.offset(b) + k)] = true;
  const detail::SaddlePointSolver saddle(mass, jac, mesh_sized);
  auto refuse = [&] {
    const Eigen::Index redundant = system.first_redundant_constraint(t_, q_);
    throw std::invalid_argument(redundant >= 0 ? system.constraint_name(redundant) + " is redundant: it repeats what "
                                                     "the constraints before it already impose (System::remove_redundant_constraints leaves such rows out)"
                                               : std::string("initial accelerations: the matrix [M J^T; J 0] is singular"));
  };
  if (!saddle.ok()) refuse();
  // A solve is good when its residual is round-off of the terms that cancel in it, ‖|K| |x|‖ + ‖b‖, not of ‖b‖ alone
  // (a 100 m beam spinning at 0.1 rad/s cancels terms of 3e8 to a right-hand side of 3e-2).
  auto solved = [&kkt](const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
    if (!x.allFinite()) return false;
    const Eigen::SparseMatrix<double> magnitudes = kkt.cwiseAbs();
    const double terms = (magnitudes * x.cwiseAbs()).norm() + b.norm();
    return (kkt * x - b).norm() <= 1e-8 * terms;
  };
  // Consistent velocities: v with Φ_q v + Φ_t = 0 (a driven joint that starts moving, or initial velocities that fight
  // a joint, would otherwise give a velocity jump and a spike in the multipliers). The bodies' rigid velocities close
  // the rows where they can, M-nearest among them with the deformation rates kept; only where they cannot, all
  // velocities, M-nearest. (M-nearest over all, a beam held at its root and given only its spin took part of the
  // root's velocity correction into its deformation rates, a kick that set it vibrating at 2 % of its size.
  // A deformation block weighted even 1e6 times in the metric still took 1 % of it: the fields' shapes
  // move an rbe3 root with little mass.)
  {
    const Eigen::VectorXd phi_t = system.constraint_time_derivative(t_, q_, options.step);
    // Row by row against the row's own terms |Φ_q| |v| + |Φ_t|: the rows carry m/s, 1/s and kg^1/2 m/s.
    const Eigen::SparseMatrix<double> jac_abs = jac.cwiseAbs();
    auto violated = [&](const Eigen::VectorXd& velocities, double tolerance) {
      const Eigen::ArrayXd violation = (jac * velocities + phi_t).cwiseAbs().array();
      const Eigen::ArrayXd terms = (jac_abs * velocities.cwiseAbs()).array() + phi_t.cwiseAbs().array();
      return (violation > tolerance * terms).any();
    };
    if (violated(v_, 1e-12)) {
      std::vector<bool> deformation(static_cast<std::size_t>(n), false);
      for (int b = 0; b < system.body_count(); ++b) {
        const BodyModel& model = system.model(b);
        for (Eigen::Index k = model.floating() ? 7 : 12; k < model.coordinate_count(); ++k)
          deformation[static_cast<std::size_t>(system.offset(b) + k)] = true;
      }
      // The rigid velocities' problem: M's rigid block, the deformation rates decoupled (identity) and out of the rows.
      std::vector<Eigen::Triplet<double>> rigid_entries;
      for (Eigen::Index k = 0; k < mass.outerSize(); ++k)
        for (Eigen::SparseMatrix<double>::InnerIterator it(mass, k); it; ++it)
          if (!deformation[static_cast<std::size_t>(it.row())] && !deformation[static_cast<std::size_t>(it.col())])
            rigid_entries.emplace_back(it.row(), it.col(), it.value());
      for (Eigen::Index k = 0; k < n; ++k)
        if (deformation[static_cast<std::size_t>(k)]) rigid_entries.emplace_back(k, k, 1.0);
      Eigen::SparseMatrix<double> rigid_metric(n, n);
      rigid_metric.setFromTriplets(rigid_entries.begin(), rigid_entries.end());
      // Its rows: those with a rigid velocity in them (a row on deformation rates alone, such as a Tisserand row of an
      // undeformed body, keeps its value: it is checked with the others below).
      std::vector<Eigen::Index> row_index(static_cast<std::size_t>(m), -1);
      Eigen::Index rigid_m = 0;
      for (Eigen::Index k = 0; k < jac.outerSize(); ++k)
        if (!deformation[static_cast<std::size_t>(k)])
          for (Eigen::SparseMatrix<double>::InnerIterator it(jac, k); it; ++it)
            if (it.value() != 0.0 && row_index[static_cast<std::size_t>(it.row())] < 0)
              row_index[static_cast<std::size_t>(it.row())] = 0;
      for (Eigen::Index r = 0; r < m; ++r)
        if (row_index[static_cast<std::size_t>(r)] == 0) row_index[static_cast<std::size_t>(r)] = rigid_m++;
      // Their right-hand side: Φ_t and what the deformation rates, which stay, already give (Tisserand rows mix both).
      Eigen::VectorXd kept = v_;
      for (Eigen::Index k = 0; k < n; ++k)
        if (!deformation[static_cast<std::size_t>(k)]) kept(k) = 0.0;
      const Eigen::VectorXd fixed_part = jac * kept + phi_t;
      std::vector<Eigen::Triplet<double>> row_entries;
      Eigen::VectorXd rigid_phi_t(rigid_m);
      for (Eigen::Index r = 0; r < m; ++r)
        if (row_index[static_cast<std::size_t>(r)] >= 0) rigid_phi_t(row_index[static_cast<std::size_t>(r)]) = fixed_part(r);
      for (Eigen::Index k = 0; k < jac.outerSize(); ++k)
        if (!deformation[static_cast<std::size_t>(k)])
          for (Eigen::SparseMatrix<double>::InnerIterator it(jac, k); it; ++it)
            if (row_index[static_cast<std::size_t>(it.row())] >= 0)
              row_entries.emplace_back(row_index[static_cast<std::size_t>(it.row())], k, it.value());
      Eigen::SparseMatrix<double> rigid_rows(rigid_m, n);
      rigid_rows.setFromTriplets(row_entries.begin(), row_entries.end());
      // The M-nearest correction over all velocities, the fallback and the yardstick.
      Eigen::VectorXd rhs(n + m);
      rhs << mass * v_, -phi_t;
      const Eigen::VectorXd nearest = saddle.solve(rhs);
      if (!solved(nearest, rhs)) refuse();
      auto energy_of = [&](const Eigen::VectorXd& change) { return change.dot(mass * change); };
      const double nearest_change = energy_of(nearest.head(n) - v_);
      Eigen::VectorXd chosen = nearest.head(n);
      const std::optional<detail::SaddlePointSolver> rigid =
          rigid_m > 0 ? std::optional<detail::SaddlePointSolver>(std::in_place, rigid_metric, rigid_rows, mesh_sized)
                      : std::nullopt;  // no row a rigid velocity reaches: nothing to factorize
      if (rigid && rigid->ok()) {
        Eigen::VectorXd rigid_rhs(n + rigid_m);
        rigid_rhs << rigid_metric * v_, -rigid_phi_t;
        const Eigen::VectorXd projected = rigid->solve(rigid_rhs);
        // Taken when it closes every row (to 1e-10 of its terms; the M-nearest solve is held to 1e-8 of its own) and
        // costs at most kRigidCorrectionRatio times the M-nearest change's kinetic energy: rows that only a deformation
        // rate holds well (a deformed spinning body's Tisserand rows) would otherwise be closed by an enormous rigid
        // velocity.
        if (projected.allFinite() && !violated(projected.head(n), 1e-10) &&
            energy_of(projected.head(n) - v_) <= kRigidCorrectionRatio * nearest_change)
          chosen = projected.head(n);
      }
      v_ = chosen;
    }
  }
  Eigen::VectorXd rhs(n + m), x;
  // With geometric stiffening the forces depend on the multipliers (the reactions at the interfaces prestress the
  // bodies): a first solve with the spin's prestress alone, a second with its multipliers. Both are exact for a body
  // that starts undeformed (K_g ξ̄ = 0 for ξ̄ = 0); one that starts deformed keeps the second solve's multipliers.
  for (int pass = 0; pass < (system.has_prestress() ? 2 : 1); ++pass) {
    system.set_prestress(t_, q_, v_, pass == 0 ? Eigen::VectorXd() : Eigen::VectorXd(x.tail(m)));
    rhs << system.forces(t_, q_, v_), -constraint_curvature(system, t_, q_, v_, scales_, options.step);
    x = saddle.solve(rhs);
    if (!solved(x, rhs)) refuse();
  }
  qdd_ = x.head(n);
  lambda_ = x.tail(m);
  a_ = qdd_;
  // Dense or sparse reduced matrix: its size is every body's kept coordinates (12, or all of a floating-frame body's)
  // and the constraint rows.
  Eigen::Index reduced_rows = m;
  for (int b = 0; b < system.body_count(); ++b) reduced_rows += system.model(b).floating() ? system.model(b).coordinate_count() : 12;
  sparse_ = options.newton_matrix == NewtonMatrix::constant_core &&
            (options.reduced_matrix == ReducedMatrix::sparse ||
             (options.reduced_matrix == ReducedMatrix::automatic && reduced_rows >= kSparseFromRows));
  std::vector<Eigen::Index> body_columns;  // each body's first coordinate, and the end
  for (int b = 0; b < system.body_count(); ++b) body_columns.push_back(system.offset(b));
  body_columns.push_back(system.coordinate_count());
  projected_ = std::make_unique<detail::ConstraintProjection>(sparse_, std::move(body_columns));
  couple_ = options.coupled_from_start;
  field_predictor_ = std::make_unique<detail::FieldPredictor>(system);
  if (options.error_tolerance > 0.0) {
    local_error_ = std::make_unique<detail::LocalError>(system, reach_, beta_ - 0.5 * gamma_ + 1.0 / 12.0, *field_predictor_);
    controller_ = std::make_unique<detail::StepController>(
        options.error_tolerance, min_step(), options.max_step > 0.0 ? options.max_step : std::numeric_limits<double>::infinity(),
        options.step);
  }
  build_solver(options.step);
}

void GeneralizedAlpha::Impl::build_solver(double h) {
  const double beta_prime = (1.0 - alpha_m_) / (beta_ * h * h * (1.0 - alpha_f_));
  const double gamma_prime = gamma_ / (beta_ * h);
  sparse_core_ = nullptr;
  if (options_.newton_matrix == NewtonMatrix::dense) {
    solver_ = std::make_unique<detail::DenseNewton>(system_, beta_prime, gamma_prime);
  } else {
    if (!cores_) cores_ = std::make_unique<detail::CoreInverses>();
    auto core = std::make_unique<detail::ConstantCoreNewton>(system_, beta_prime, gamma_prime, sparse_, *cores_);
    if (sparse_) sparse_core_ = core.get();
    solver_ = std::move(core);
  }
  solver_step_ = h;
  field_predictor_->set_step(h);
  if (local_error_) local_error_->set_step(h);
  refresh_ = true;
}

void GeneralizedAlpha::Impl::build_sparse_coupling(double t1, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                                   const Eigen::VectorXd& qdd, const Eigen::VectorXd& mu, double h,
                                                   double gamma_prime) {
  const Eigen::SparseMatrix<double> rate = detail::constraint_rate(system_, t1, q, v, scales_, h, gamma_prime);  // Z/γ'
  // P = W Φ_q(q_f)ᵀ: the direction of ν's correction (position_correction), with q_f this iterate
  const Eigen::SparseMatrix<double, Eigen::RowMajor> direction = squared_scales_.asDiagonal() * work_.jacobian.transpose();
  const Eigen::SparseMatrix<double> projected = work_.jacobian * direction;
  sparse_core_->factor_coupled(t1, q, v, qdd, mu, work_.jacobian, rate, direction, projected);
}

GeneralizedAlpha::Impl::~Impl() = default;

}  // namespace flexbody::runtime
