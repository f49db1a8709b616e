#include "flexbody/runtime/generalized_alpha.hpp"

#include "constraint_projection.hpp"
#include "newton_solvers.hpp"
#include "saddle_point.hpp"
#include "stabilized_coupling.hpp"

#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

namespace flexbody::runtime {
namespace {

// d/dt (Φ_q q̇ + Φ_t) at fixed q̇, by central differences along (q + s q̇, t + s): the acceleration-level
// right-hand side of the consistent initial accelerations (a directional derivative). The step is ∛ε over the fastest
// relative rate of a coordinate, |q̇_i| / (|q_i| + scale_i), or 1/h, as constraint_rate's (stabilized_coupling.cpp):
// truncation and rounding both ~ε^⅔ of the terms. (A fixed 1e-6 s differenced a 1 mm part spinning at 3.3e5 rad/s
// over 0.3 rad, and its initial accelerations were off by 40 %, issue 29's scale test.)
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

// Whether every entry is finite, in one vectorized pass: a NaN or an infinity in any entry makes the sum NaN or
// infinite. (Eigen's allFinite() tests entry by entry; a sum of finite entries could only overflow near 1e308,
// which is no state to go on from either.)
bool all_finite(const Eigen::VectorXd& x) { return std::isfinite(x.sum()); }

// ∫|u|² dm of body b's elastic displacement [kg m²]: ξ̄ᵀ (G_ff ⊗ I3) ξ̄ (and |ξ̄| = |ξ| for orthogonal A, so without
// rotating). A floating-frame body's ξ̄ = Σ η_m c_m, the modes without the rigid part an interface frame gives them:
// ηᵀ M_ff η would count that rigid motion as deformation (a rod in its crank-end frame was stopped at "2 % RMS" while
// the same motion in the mean-axis frame was at 0.4 %).
double elastic_mass_norm_squared(const System& system, int b, const Eigen::VectorXd& q) {
  const BodyModel& model = system.model(b);
  const Eigen::Index o = system.offset(b), n = model.coordinate_count();
  if (model.floating())
    return field_mass_norm_squared(model, ffrf_field_coordinates(*model.floating_frame, q.segment(o, n)));
  return field_mass_norm_squared(model, q.segment(o + 12, n - 12));
}

// Round-off floor of Newton's corrections, relative to |q_i| + scale_i: a constraint row's residual is a sum of a few
// products of coordinates, so its rounding is a few ε |q|, and so is the correction it asks for. Measured: the
// corrections of a flexible pendulum stagnate at 1-2 ε (|q_i| + scale_i); 8 ε stops there without a false stop.
constexpr double kRoundOffFloor = 8.0 * std::numeric_limits<double>::epsilon();
// Corrections that stagnate within this many round-off floors (~2e-12 of the positions) end the iteration.
constexpr double kStagnationFloors = 1000.0;
// The initial velocities' correction by the rigid velocities alone is taken while its kinetic energy is at most this
// many times the M-nearest correction's over all velocities (GeneralizedAlpha's constructor). Measured: the beam driven
// at its rbe3 root in the scale test 20 times (the M-nearest one moved the root through the modes' rotation), the
// pinned beam of fast_spin_test 1.0; a deformed tumbling beam's Tisserand rows 4e31 times (rejected).
constexpr double kRigidCorrectionRatio = 100.0;

// The length scale of each of one body's coordinates (GeneralizedAlphaOptions::tolerance): the radius of gyration
// r = √(tr J / m) for τ, 1 for vec(A) (δa moves a point at distance r by r δa, as δτ = r δa would), and for a field
// coordinate the amplitude whose largest nodal displacement is r: r / max_i |Ῡ'(i, f)|. The full-order body's fields
// are the nodal displacements themselves (Ῡ' = I) or its rbe2 sets' affine fields, scaled to at most 1; a model built without its fields takes the RMS displacement,
// r √(m / G_ff(f, f)).
void append_scales(const BodyModel& model, Eigen::VectorXd& scales, Eigen::Index offset) {
  const double trace = model.g_border(1, 1) + model.g_border(2, 2) + model.g_border(3, 3);
  const double r = std::sqrt(std::max(trace, 0.0) / model.mass);
  scales.segment(offset, 3).setConstant(r);
  if (model.floating()) {
    // Euler parameters: δp turns the body by 2 |δp|, moving a point at r by 2 r |δp|: scale ½. A modal coordinate:
    // the amplitude whose largest nodal displacement is r (each node's displacement in the mode, W_mᵀ Y(i, :)ᵀ).
    const FfrfModel& f = *model.floating_frame;
    scales.segment(offset + 3, 4).setConstant(0.5);
    const bool has_fields = model.fields.cols() == model.field_count() && model.fields.rows() == model.nodes.rows();
    for (Eigen::Index m = 0; m < f.modes; ++m) {
      double largest = 0.0;
      const auto w = f.shapes.middleCols<3>(3 * m);
      for (Eigen::Index i = 0; has_fields && i < model.nodes.rows(); ++i) {
        const Eigen::Vector3d u = w.row(0).transpose() + w.middleRows<3>(1).transpose() * model.nodes.row(i).transpose() +
                                  w.bottomRows(model.field_count()).transpose() * model.fields.row(i).transpose();
        largest = std::max(largest, u.norm());
      }
      scales(offset + 7 + m) = largest > 0.0 ? r / largest : r * std::sqrt(model.mass / f.modal_mass(m, m));
    }
    return;
  }
  scales.segment(offset + 3, 9).setConstant(1.0);
  for (Eigen::Index f = 0; f < model.field_count(); ++f) {
    double scale = r;
    if (!model.sparse && model.fields.cols() == model.field_count() && model.fields.rows() > 0)
      scale = r / model.fields.col(f).cwiseAbs().maxCoeff();
    else if (!model.sparse)
      scale = r * std::sqrt(model.mass / model.mass_matrix(4 + f, 4 + f));
    scales.segment(offset + 12 + 3 * f, 3).setConstant(scale);
  }
}

}  // namespace

void GeneralizedAlpha::check_deformation(double t, const Eigen::VectorXd& q) const {
  if (!(options_.deformation_limit > 0.0)) return;
  for (int b = 0; b < system_.body_count(); ++b) {
    const BodyModel& model = system_.model(b);
    if (model.rigid()) continue;
    double squared = 0.0;
    if (model.floating()) {  // ηᵀ Γ η with Γ = Cᵀ (G_ff ⊗ I3) C: the same as ‖Σ η_k c_k‖², without a vector of 3 n_f
      const Eigen::MatrixXd& gram = modal_grams_[static_cast<std::size_t>(b)];
      const auto eta = q.segment(system_.offset(b) + 7, gram.rows());
      for (Eigen::Index k = 0; k < gram.rows(); ++k) squared += eta(k) * gram.col(k).dot(eta);
    } else {
      squared = elastic_mass_norm_squared(system_, b, q);
    }
    const double rms = std::sqrt(std::max(squared, 0.0) / model.mass);
    const double size = body_sizes_[static_cast<std::size_t>(b)];
    if (rms > options_.deformation_limit * size) {
      std::ostringstream why;
      why << "t = " << t << " s: body '" << system_.body_name(b) << "' left the small-deformation range of its linear "
          << "model: RMS elastic displacement " << rms << " m = " << 100.0 * rms / size << " % of its size (limit "
          << 100.0 * options_.deformation_limit << " %). ";
      if (prestress_gaps_[static_cast<std::size_t>(b)].empty())
        why << "Its model is linear in the deformation (its geometric stiffening covers the prestress, not large "
            << "deformation): a load beyond linear elasticity, or a spin beyond the stiffened model's range";
      else
        why << "The model has no geometric stiffening for it (FORMULATION.md section 8): a spin above the first "
            << "bending frequency, or a load beyond linear elasticity";
      throw StepFailure(why.str());
    }
  }
}

void GeneralizedAlpha::check_spin(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  for (int b = 0; b < system_.body_count(); ++b) {
    const BodyModel& model = system_.model(b);
    if (model.rigid() || !(model.lowest_frequency_hz > 0.0)) continue;
    const std::string& gap = prestress_gaps_[static_cast<std::size_t>(b)];
    const bool stiffened = gap.empty();
    const double warning = stiffened ? options_.stiffened_spin_warning : options_.spin_warning;
    const double limit = stiffened ? options_.stiffened_spin_limit : options_.spin_limit;
    if (!(warning > 0.0) && !(limit > 0.0)) continue;
    const double spin = system_.angular_velocity(b, q, v).norm();
    const double ratio = spin / (2.0 * std::numbers::pi * model.lowest_frequency_hz);
    const bool over_limit = limit > 0.0 && ratio > limit;
    const bool warn = warning > 0.0 && ratio > warning && !spin_warned_[static_cast<std::size_t>(b)];
    if (!over_limit && !warn) continue;  // the message only when it is said: this runs every step
    std::ostringstream what;
    what << "t = " << t << " s: body '" << system_.body_name(b) << "' spins at " << spin << " rad/s = " << ratio
         << " of its lowest elastic frequency (" << model.lowest_frequency_hz << " Hz); ";
    if (stiffened) {
      what << "its geometric stiffening was verified up to 2 times that frequency (a rotating cantilever within "
           << "0.12 %); beyond, the fixed modes and the terms still left out (large deformation, the modes' change with "
           << "the speed) limit it, and the improved GCMS showed a spurious mode in the plane of rotation at 3-4 times "
           << "it (FORMULATION.md section 8.1)";
    } else {
      what << "a linear corotational model has no centrifugal stiffening (FORMULATION.md section 8), so its "
           << "deformation is wrong by about " << 100.0 * 0.36 * ratio * ratio << " % in the spin plane and "
           << 100.0 * 1.2 * ratio * ratio << " % out of it";
      if (model.prestress) what << " (" << gap << ")";
    }
    if (over_limit) {
      what << " (limit: " << limit << " of it)";
      throw StepFailure(what.str());
    }
    spin_warned_[static_cast<std::size_t>(b)] = 1;
    what << " (warning above " << warning << " of it)";
    warnings_.push_back(what.str());
  }
}

// Why a step may have failed, from the last converged state (the failed iterate says nothing reliable): the body
// that turned most per step, and the one closest to the deformation limit.
std::string GeneralizedAlpha::last_state_diagnosis() const {
  const double h = options_.step;
  int fastest = -1, most_deformed = -1;
  double largest_turn = 0.0, largest_share = 0.0, rms_of_most = 0.0;
  for (int b = 0; b < system_.body_count(); ++b) {
    const double turn = system_.angular_velocity(b, q_, v_).norm() * h;
    if (!(turn <= largest_turn)) largest_turn = turn, fastest = b;  // a non-finite rate is the one to report
    const BodyModel& model = system_.model(b);
    const double size = body_sizes_[static_cast<std::size_t>(b)];
    if (model.rigid() || !(size > 0.0)) continue;
    const double squared = elastic_mass_norm_squared(system_, b, q_);
    const double rms = std::sqrt(std::max(squared, 0.0) / model.mass);
    if (!(rms / size < largest_share)) largest_share = rms / size, most_deformed = b, rms_of_most = rms;
  }
  std::ostringstream out;
  out << "; at the last converged step, t = " << t_ << " s,";
  if (fastest >= 0)
    out << " body '" << system_.body_name(fastest) << "' turned " << largest_turn << " rad per step"
        << (largest_turn > 0.1 ? " (more than 0.1 rad per step: try a smaller step)" : "");
  if (most_deformed >= 0)
    out << (fastest >= 0 ? " and" : "") << " body '" << system_.body_name(most_deformed) << "' had an RMS elastic "
        << "displacement of " << rms_of_most << " m = " << 100.0 * largest_share << " % of its size ("
        << (options_.deformation_limit > 0.0 ? "limit " + std::to_string(100.0 * options_.deformation_limit) + " %"
                                             : std::string("no limit set")) << ")";
  if (fastest < 0 && most_deformed < 0) out << " every body was at rest and undeformed";
  return out.str();
}

GeneralizedAlpha::GeneralizedAlpha(const System& system, const GeneralizedAlphaOptions& options, double t0)
    : system_(system), options_(options), t0_(t0), t_(t0), coupling_(std::make_unique<detail::StabilizedCoupling>()) {
  const double rho = options.rho_infinity;
  if (!(rho >= 0.0 && rho <= 1.0)) throw std::invalid_argument("generalized-alpha: rho_inf must lie in [0, 1]");
  if (!(options.step > 0.0) || !std::isfinite(options.step))
    throw std::invalid_argument("generalized-alpha: the step must be positive");
  if (options.max_iterations < 1 || !(options.tolerance > 0.0 && options.tolerance <= kLargestTolerance) ||
      !(options.deformation_limit >= 0.0) || !(options.spin_warning >= 0.0) || !(options.spin_limit >= 0.0) ||
      !(options.stiffened_spin_warning >= 0.0) || !(options.stiffened_spin_limit >= 0.0))
    throw std::invalid_argument("generalized-alpha: max_iterations >= 1, 0 < tolerance <= 1e-3 (relative to each step's "
                                "predictor-corrector distance), and deformation_limit and the spin levels (spin_warning, "
                                "spin_limit, stiffened_spin_warning, stiffened_spin_limit) >= 0 are required");
  alpha_m_ = (2.0 * rho - 1.0) / (rho + 1.0);
  alpha_f_ = rho / (rho + 1.0);
  gamma_ = 0.5 + alpha_f_ - alpha_m_;
  beta_ = 0.25 * (gamma_ + 0.5) * (gamma_ + 0.5);
  q_ = system.initial_coordinates();
  v_ = system.initial_velocities();
  scales_.resize(q_.size());
  reach_.resize(q_.size());
  for (int b = 0; b < system.body_count(); ++b) {
    append_scales(system.model(b), scales_, system.offset(b));
    const Eigen::Index o = system.offset(b), n_b = system.model(b).coordinate_count();
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
  for (int b = 0; b < system.body_count(); ++b) {  // bounding-box diagonals, for the deformation limit
    const format::RowMatrixX3d& nodes = system.model(b).nodes;
    body_sizes_.push_back(nodes.rows() ? (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).norm() : 0.0);
  }
  modal_grams_.resize(static_cast<std::size_t>(system.body_count()));
  for (int b = 0; b < system.body_count(); ++b) {  // Γ_kl = c_kᵀ (G_ff ⊗ I3) c_l, by polarisation of the mass norm
    const BodyModel& model = system.model(b);
    if (!model.floating()) continue;
    const Eigen::Index modes = model.coordinate_count() - 7;
    Eigen::VectorXd q_b = Eigen::VectorXd::Zero(7 + modes);
    q_b(3) = 1.0;
    std::vector<Eigen::VectorXd> c(static_cast<std::size_t>(modes));
    for (Eigen::Index k = 0; k < modes; ++k) {
      q_b(7 + k) = 1.0;
      c[static_cast<std::size_t>(k)] = ffrf_field_coordinates(*model.floating_frame, q_b);
      q_b(7 + k) = 0.0;
    }
    Eigen::MatrixXd& gram = modal_grams_[static_cast<std::size_t>(b)];
    gram.resize(modes, modes);
    for (Eigen::Index k = 0; k < modes; ++k)
      for (Eigen::Index l = 0; l <= k; ++l) {
        const Eigen::VectorXd &ck = c[static_cast<std::size_t>(k)], &cl = c[static_cast<std::size_t>(l)];
        gram(k, l) = gram(l, k) = 0.25 * (field_mass_norm_squared(model, ck + cl) - field_mass_norm_squared(model, ck - cl));
      }
  }
  const Eigen::Index n = q_.size(), m = system.constraint_count();
  const Eigen::VectorXd phi = system.constraints(t_, q_);
  for (Eigen::Index k = 0; k < m; ++k)
    if (std::abs(phi(k)) > 1e-8)
      throw std::invalid_argument("initial state violates " + system.constraint_name(k) + " by " + std::to_string(phi(k)) +
                                  " (runtime::assemble closes the joints' gaps; assembly.hpp)");
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
  // (issue 12: a 100 m beam spinning at 0.1 rad/s cancels terms of 3e8 to a right-hand side of 3e-2).
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
  // root's velocity correction into its deformation rates, a kick that set it vibrating at 2 % of its size; issue 29's
  // scale test. A deformation block weighted even 1e6 times in the metric still took 1 % of it: the fields' shapes
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
  build_solver(options.step);
}

void GeneralizedAlpha::build_solver(double h) {
  const double beta_prime = (1.0 - alpha_m_) / (beta_ * h * h * (1.0 - alpha_f_));
  const double gamma_prime = gamma_ / (beta_ * h);
  sparse_core_ = nullptr;
  if (options_.newton_matrix == NewtonMatrix::dense) {
    solver_ = std::make_unique<detail::DenseNewton>(system_, beta_prime, gamma_prime);
  } else {
    auto core = std::make_unique<detail::ConstantCoreNewton>(system_, beta_prime, gamma_prime, sparse_);
    if (sparse_) sparse_core_ = core.get();
    solver_ = std::move(core);
  }
  solver_step_ = h;
  refresh_ = true;
}

void GeneralizedAlpha::build_sparse_coupling(double t1, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                             const Eigen::VectorXd& qdd, const Eigen::VectorXd& mu, double h,
                                             double gamma_prime) {
  const Eigen::SparseMatrix<double> rate = detail::constraint_rate(system_, t1, q, v, scales_, h, gamma_prime);  // Z/γ'
  // P = W Φ_q(q_f)ᵀ: the direction of ν's correction (advance's correction_of), with q_f this iterate
  const Eigen::SparseMatrix<double, Eigen::RowMajor> direction = squared_scales_.asDiagonal() * work_.jacobian.transpose();
  const Eigen::SparseMatrix<double> projected = work_.jacobian * direction;
  sparse_core_->factor_coupled(t1, q, v, qdd, mu, work_.jacobian, rate, direction, projected);
}

GeneralizedAlpha::~GeneralizedAlpha() = default;

void GeneralizedAlpha::step() {
  advance(options_.step, t0_ + static_cast<double>(steps_ + 1) * options_.step);
  ++steps_;
}

void GeneralizedAlpha::step_to(double t_end) {
  const double h = t_end - t_;
  // t_ after many steps carries the rounding of t0 + k h, about ε |t_end|: beyond 1e7 steps that exceeds 1e-9 h.
  const double slack = std::max(kStepToSlack * options_.step, 8.0 * std::numeric_limits<double>::epsilon() * std::abs(t_end));
  if (!(h > 0.0) || !(h <= options_.step + slack))
    throw std::invalid_argument("generalized-alpha: step_to(" + std::to_string(t_end) + ") from t = " +
                                std::to_string(t_) + " s is not a step of at most " + std::to_string(options_.step) +
                                " s forward");
  advance(h, t_end);
  t0_ = t_end;  // later steps: t0 + k h from here
  steps_ = 0;
}

void GeneralizedAlpha::advance(double h, double t1) {
  const Eigen::Index n = q_.size(), m = lambda_.size();
  // β' and γ' of the solver's matrix are those of the step it was built for; a step size changed beyond rounding
  // rebuilds it (step_to), a kept one is a modified Newton matrix (GeneralizedAlphaOptions::reuse_newton_matrix).
  if (std::abs(h - solver_step_) > kStepToSlack * solver_step_) build_solver(h);
  const double beta_prime = (1.0 - alpha_m_) / (beta_ * h * h * (1.0 - alpha_f_));
  const double gamma_prime = gamma_ / (beta_ * h);
  // The iterate, kept as members so that their storage is reused from step to step.
  Eigen::VectorXd &qdd = work_.qdd, &a = work_.a, &v = work_.v, &q = work_.q, &mu = work_.mu, &dx = work_.dx;
  Eigen::VectorXd& residual = work_.residual;  // the dynamic rows, scaled by 1/β'; the constraint rows are Φ
  // A Newton matrix kept from earlier iterations and steps (modified Newton) is refreshed when the corrections
  // stop shrinking fast (ratio > 1/4); a step that does not converge with a kept matrix is retried with a fresh one.
  bool fresh_this_step = false;
  const bool stabilized = options_.constraints == ConstraintForm::stabilized_index2 && m > 0;
  Eigen::SparseMatrix<double>& jacobian = work_.jacobian;
  Eigen::VectorXd &velocity_rows = work_.velocity_rows, &position_step = work_.position_step;
  // The position correction W Φ_q(q_f)ᵀ ν along the Jacobian of the kept Newton matrix (q_f the iterate where it was
  // built, before ν's correction was turned to it), the one its factor of Φ_q W Φ_qᵀ holds: then a correction Δν
  // meets the position rows up to (Φ_q(q) − Φ_q(q_f)) W Φ_q(q_f)ᵀ Δν. With the direction Φ_q(q_n) of the step's
  // start and the factor from q_f, the mismatch had both Jacobians in it and, through (Φ_q W Φ_qᵀ)⁻¹, grew with the
  // scene's weakest constraint mode: a chain of 64 rigid links (its out-of-plane bending) contracted by 0.86 per
  // iteration and needed the coupled step at t = 0.019 s; with this direction it converges in 4.6 iterations per
  // step (bench/README.md "scale_bench").
  // The converged step then moves along q_f's normal rather than q_n's: bench/convergence_bench's errors changed
  // by -0.3 to +1.1 % (rigid pendulum, heavy top, flexible pendulum, 4e-4 to 1e-5 s), the orders not at all.
  // `work_.shift` is the whole W Φ_q(q_f)ᵀ ν in q; a new Newton matrix moves it to the new Jacobian's direction.
  auto correction_of = [&](const Eigen::VectorXd& nu, Eigen::VectorXd& out) {
    out.noalias() = jacobian.transpose() * nu;
    out.array() *= squared_scales_.array();
  };
  // Why the first attempt that diverged did: the step fails with it unless a fresh matrix or the coupled step (below)
  // gets through.
  std::string failure;
  auto diverged = [&](const Eigen::VectorXd& phi) {
    std::ostringstream why;
    Eigen::Index worst = 0;
    if (m > 0) phi.cwiseAbs().maxCoeff(&worst);
    why << "t = " << t1 << " s: the Newton iteration diverged or its matrix is singular: a correction was not finite at "
        << "iteration " << iterations_ << " (largest constraint residual in "
        << (m > 0 ? system_.constraint_name(worst) : std::string("none")) << ")" << last_state_diagnosis();
    if (failure.empty()) failure = why.str();
  };
  if (fresh_starts_ > 0) {
    refresh_ = true;
    --fresh_starts_;
  }
  const bool kept_at_start = !refresh_ && options_.reuse_newton_matrix;  // a trial of the kept matrix
  for (int attempt = 0;; ++attempt) {
    // Predictor: q̈_{n+1} = q̈_n.
    qdd = qdd_;
    a = (alpha_f_ * qdd_ - alpha_m_ * a_ + (1.0 - alpha_f_) * qdd) / (1.0 - alpha_m_);
    v = v_ + h * (1.0 - gamma_) * a_ + h * gamma_ * a;
    q = q_ + h * v_ + h * h * (0.5 - beta_) * a_ + h * h * beta_ * a;
    mu = lambda_ / beta_prime;  // the scaled multipliers
    work_.predicted = q;
    if (stabilized) {
      // ν changes slowly from step to step (it is the Newmark update's drift off Φ = 0 over one step): starting from
      // the last step's ν leaves the first iteration a small Δν, whose effect on the dynamic rows is only seen at the
      // next iteration (measured: a flexible pendulum needed 3.1-3.6 iterations per step from ν = 0).
      if (nu_.size() != m) nu_ = Eigen::VectorXd::Zero(m);
      work_.nu = nu_;
      if (jacobian.rows() == m)
        correction_of(nu_, work_.shift);
      else
        work_.shift.setZero(n);  // the first step: no Newton matrix yet, and ν = 0
      q += work_.shift;
    }
    // The world's extent [m]: joints and springs compare positions of this size, so their residuals round at ε times
    // it, wherever the body is (a pendulum pivoted 100 m from the origin).
    double extent = ground_extent_;
    for (int b = 0; b < system_.body_count(); ++b) extent = std::max(extent, q_.segment<3>(system_.offset(b)).norm());
    double previous_correction = std::numeric_limits<double>::infinity();
    double rate = std::numeric_limits<double>::infinity();  // unknown until a second iteration measures it
    bool converged = false;
    bool slow = false;  // a correction shrank less than fourfold in this attempt: the kept matrix may be stale
    for (iterations_ = 1; iterations_ <= options_.max_iterations; ++iterations_) {
      Eigen::VectorXd& phi = work_.phi;
      auto evaluate_residual = [&] {  // the scaled dynamic rows at the iterate: (M q̈ − f)/β' + Φ_qᵀ μ
        system_.dynamic_residual(t1, q, v, qdd, residual, false);  // a floating-frame body's in one pass
        residual *= 1.0 / beta_prime;  // a product: a division per entry costs more than the rest of this line
        system_.add_constraint_jacobian_transpose_product(t1, q, mu, residual);
        // The geometric stiffness weighted by the spin and the joint reactions at this iterate (prestress.hpp), from
        // the joints' evaluations just made.
        system_.add_prestress_residual(t1, q, v, mu, beta_prime, residual);
      };
      bool evaluated = false;
      const bool refresh = refresh_ || !options_.reuse_newton_matrix;
      if (refresh) {
        system_.sparse_constraint_jacobian(t1, q, jacobian);
        if (stabilized) {  // ν's correction so far, along the new Jacobian (correction_of)
          q -= work_.shift;
          correction_of(work_.nu, work_.shift);
          q += work_.shift;
        }
        // The coupled stabilised step with a sparse reduced matrix builds its own system (below).
        const bool sparse_coupled = stabilized && couple_ && sparse_core_ != nullptr;
        // A floating-frame body's tangent and the dense matrix carry K_g: weigh it at this iterate, not at the last
        // one evaluated (after a failed attempt, that one may be far off or not finite; helper review of e1a02b5).
        if (system_.has_prestress()) system_.set_prestress(t1, q, v, mu, beta_prime);
        if (!sparse_coupled) solver_->factor(t1, q, v, qdd, mu, jacobian);
        if (stabilized) {
          if (!projected_->factor(jacobian, squared_scales_)) {  // Φ_q W Φ_qᵀ
            if (iterations_ > 1) {  // rows independent at the predictor lost it at a diverging iterate
              if (failure.empty())
                failure = "t = " + std::to_string(t1) + " s: the Newton iteration diverged: at iteration " +
                          std::to_string(iterations_) + " the constraint rows became dependent (Φ_q W Φ_qᵀ is not "
                          "positive definite)" + last_state_diagnosis();
              break;
            }
            throw StepFailure("t = " + std::to_string(t1) + " s: the constraint rows are dependent (Φ_q W Φ_qᵀ is not "
                              "positive definite)" + last_state_diagnosis());
          }
          coupled_ = couple_;  // the coupled step, once a step failed with the alternating one (below)
          if (sparse_coupled) {
            build_sparse_coupling(t1, q, v, qdd, mu, h, gamma_prime);
          } else if (coupled_) {
            evaluate_residual();
            evaluated = true;
            const Eigen::MatrixXd direction = squared_scales_.asDiagonal() * Eigen::MatrixXd(jacobian).transpose();
            if (!coupling_->build(system_, *solver_, t1, q, v, qdd, mu, Eigen::MatrixXd(jacobian), direction, residual,
                                  scales_, beta_prime, gamma_prime, h)) {
              if (failure.empty())
                failure = "t = " + std::to_string(t1) + " s: the coupling of the position and velocity rows "
                          "(stabilised index-2) is not finite" + last_state_diagnosis();
              break;
            }
          }
        }
        refresh_ = false;
        extra_iterations_ = 0;
        fresh_this_step = true;
        ++factorizations_;
      }
      // The rows after a new Newton matrix, which may have moved ν's correction to its Jacobian's direction.
      if (stabilized) {
        system_.constraints_and_rates(t1, q, v, phi, velocity_rows);  // Φ and Φ_q v, each joint evaluated once
        if (time_dependent_) system_.add_constraint_time_derivative(t1, q, h, velocity_rows);
        velocity_rows /= gamma_prime;
      } else {
        system_.constraints(t1, q, phi);
      }
      if (stabilized && !coupled_) {
        // Alternating: position rows first. The Newmark correction δ (v += γ' δ, q̈ += β' δ) will meet the velocity
        // rows, γ' Φ_q δ = −Ψ with Ψ = Φ_q v + Φ_t; the position rows are then met by ν alone: Φ_q W Φ_qᵀ Δν =
        // −Φ − Φ_q δ = −Φ + Ψ/γ'. The position moves by W Φ_qᵀ Δν before the dynamic rows are evaluated, so that δ
        // sees it in the same iteration (with the move applied one iteration late, the corrections of the two
        // cancelled and the stopping test ended the iteration early: velocities off by 6.5e-7 of 3 m/s, helper
        // review of 77a5e2a).
        work_.nu_step = velocity_rows - phi;
        projected_->solve_in_place(work_.nu_step);
        correction_of(work_.nu_step, position_step);
        if (!all_finite(position_step)) {
          diverged(phi);
          break;
        }
        work_.nu += work_.nu_step;
        work_.shift += position_step;
        q += position_step;
        evaluate_residual();
        solver_->solve(q, residual, velocity_rows, dx);
        if (!all_finite(dx)) {
          diverged(phi);
          break;
        }
      } else {
        // Index-3, or the coupled stabilised step: the index-3 system's solve, then Δν from the velocity rows, which
        // couple through Z = dΦ_q/dt (stabilized_coupling.hpp).
        if (!evaluated) evaluate_residual();
        if (stabilized && sparse_core_) {  // the sparse coupled step: [δ'; Δμ; Δν] at once, δ = δ' − P Δν
          sparse_core_->solve_coupled(q, residual, phi, velocity_rows, work_.coupled);
          work_.nu_step = work_.coupled.tail(m);
          correction_of(work_.nu_step, position_step);
          dx.resize(n + m);
          dx.head(n) = work_.coupled.head(n) - position_step;
          dx.tail(m) = work_.coupled.segment(n, m);
          if (!all_finite(position_step) || !all_finite(dx)) {
            diverged(phi);
            break;
          }
          work_.nu += work_.nu_step;
          work_.shift += position_step;
          q += position_step;
        } else {
          solver_->solve(q, residual, phi, dx);
          if (!all_finite(dx)) {
            diverged(phi);
            break;
          }
          if (stabilized) {
            coupling_->complete(dx, phi, velocity_rows, work_.nu_step);
            correction_of(work_.nu_step, position_step);
            if (!all_finite(position_step) || !all_finite(dx)) {
              diverged(phi);
              break;
            }
            work_.nu += work_.nu_step;
            work_.shift += position_step;
            q += position_step;
          }
        }
      }
      q += dx.head(n);
      v += gamma_prime * dx.head(n);
      qdd += beta_prime * dx.head(n);
      mu += dx.tail(m);
      // The stopping test (GeneralizedAlphaOptions::tolerance), in each coordinate's length scale: the remaining
      // error ρ/(1 − ρ) |Δq| against tolerance × |q − q_pred|, or |Δq| at the round-off of the coordinate and of the
      // world positions it moves (8 ε (|q_i| + scale_i + reach_i × extent)) and, in the stabilised form, γ' |δ_i|
      // at the round-off of the velocity. |Δq_i| is |δ_i| + |W Φ_qᵀ Δν|_i: the two must not cancel in the test.
      double correction = 0.0, distance = 0.0, above_floor = 0.0;
      double above_velocity_floor = 0.0;
      const double speed = stabilized ? (v.cwiseAbs().array() / scales_.array()).maxCoeff() : 0.0;  // fastest [1/s]
      for (Eigen::Index i = 0; i < n; ++i) {
        const double step_i = std::abs(dx(i)) + (stabilized ? std::abs(position_step(i)) : 0.0), inverse = 1.0 / scales_(i);
        correction = std::max(correction, step_i * inverse);
        distance = std::max(distance, std::abs(q(i) - work_.predicted(i)) * inverse);
        above_floor = std::max(above_floor, step_i / (kRoundOffFloor * (std::abs(q(i)) + scales_(i) + reach_(i) * extent)));
        if (stabilized) {
          const double velocity_step = gamma_prime * std::abs(dx(i));
          above_velocity_floor = std::max(above_velocity_floor, velocity_step / (kRoundOffFloor * (std::abs(v(i)) + scales_(i) * speed)));
        }
      }
      if (iterations_ > 1 && previous_correction > 0.0) rate = correction / previous_correction;
      const double remaining = rate < 1.0 ? correction * rate / (1.0 - rate) : std::numeric_limits<double>::infinity();
      // Corrections that stopped shrinking within kStagnationFloors floors are round-off of a source the floor does
      // not know: the rounding of the linear solve, whose saddle-point matrix can have a condition number of 1e14
      // (helper review of 77a5e2a: a 1 mm bar on the tip of a 100 m bar repeated a correction of 250 floors).
      const bool stagnated = iterations_ > 2 && rate > 0.5 && above_floor <= kStagnationFloors;
      const bool at_round_off = (above_floor <= 1.0 && above_velocity_floor <= 1.0) || stagnated;
      if (at_round_off || remaining <= options_.tolerance * distance) {
        // Slow contraction that ends at round-off says nothing about the matrix: keep it (helper review: the rigid
        // pendulum at h = 1e-5 s rebuilt it 121 times instead of once).
        if (at_round_off && slow) refresh_ = false;
        converged = true;
        break;
      }
      // Judged against a correction of the same matrix: the first one of a matrix built in this iteration follows
      // one of the stale matrix (helper review: counting it rebuilt a fresh matrix at once, two builds per step).
      if (!refresh && correction > 0.25 * previous_correction) refresh_ = slow = true;
      previous_correction = correction;
    }
    if (converged) break;
    // A step that failed is tried again from its predictor (in the stabilised form moved by the last step's ν along the
    // last Jacobian built, which a fresh matrix then turns to its own): with a fresh matrix if its matrix was kept,
    // then (stabilised form) with the coupled step; a failure of the last resort stops the run with the reason.
    if (attempt == 0 && !fresh_this_step) {  // the kept matrix was too old: once more with a fresh one
      refresh_ = true;
      continue;
    }
    if (stabilized && !couple_) {  // (couple_, not coupled_: an attempt may fail before its matrix is built)
      // A fresh matrix did not converge with the alternating step: once more with the coupled one, which then stays
      // for the rest of the run (stabilized_coupling.hpp; slower to build, so not used before it is needed).
      couple_ = refresh_ = true;
      const std::string cost = sparse_core_ != nullptr
                                   ? "one sparse factorization of n + 2m unknowns"
                                   : "m solves";
      warnings_.push_back("t = " + std::to_string(t1) + " s: Newton did not converge with the stabilised index-2 "
                          "form's alternating step; the run continues with its coupled step, which costs " + cost +
                          " per Newton matrix (n = " + std::to_string(n) + " coordinates, m = " + std::to_string(m) +
                          " constraint rows)");
      continue;
    }
    if (!failure.empty()) throw StepFailure(failure);
    Eigen::Index worst = 0;
    const Eigen::VectorXd now = system_.constraints(t1, q);
    if (m > 0) now.cwiseAbs().maxCoeff(&worst);
    std::ostringstream why;
    why << "t = " << t1 << " s: Newton did not converge in " << options_.max_iterations
        << " iterations (largest constraint residual " << (m > 0 ? now.cwiseAbs().maxCoeff() : 0.0) << " in "
        << (m > 0 ? system_.constraint_name(worst) : std::string("none")) << ")" << last_state_diagnosis();
    throw StepFailure(why.str());
  }
  if (!all_finite(q) || !all_finite(v) || !all_finite(qdd)) throw StepFailure("t = " + std::to_string(t1) + " s: non-finite state");
  check_deformation(t1, q);
  check_spin(t1, q, v);
  a = (alpha_f_ * qdd_ - alpha_m_ * a_ + (1.0 - alpha_f_) * qdd) / (1.0 - alpha_m_);
  q_ = q;
  v_ = v;
  qdd_ = qdd;
  a_ = a;
  lambda_ = beta_prime * mu;
  if (stabilized) nu_ = work_.nu;
  // A kept matrix slowly goes stale as the bodies rotate away from where it was built: steps then need a third
  // or fourth iteration. Once such extra iterations add up to about the cost of building a new matrix (a build is
  // ~10 iterations' work: the elastic tangent and ~20 core products against 2-3 per iteration), rebuild it.
  if (kept_at_start) {
    fresh_start_backoff_ = fresh_this_step ? std::min(2 * fresh_start_backoff_ + 1, kLongestFreshStarts) : 0;
    fresh_starts_ = fresh_start_backoff_;
  }
  if (!fresh_this_step) extra_iterations_ += std::max(0, iterations_ - 2);  // a fresh matrix is not stale
  if (extra_iterations_ >= kExtraIterationsPerRebuild) refresh_ = true;
  t_ = t1;
  total_iterations_ += iterations_;
}

}  // namespace flexbody::runtime
