#include "newton_solvers.hpp"

#include "../kernels/dense_product.hpp"
#include "../kernels/parallel.hpp"

#include "flexbody/runtime/gcms_elastic.hpp"
#include "flexbody/runtime/reference_constraints.hpp"

#include <algorithm>
#include <stdexcept>

namespace flexbody::runtime::detail {
namespace {

// y = Â x for x of length 3 n_f (block diagonal A).
Eigen::MatrixXd rotate(const Eigen::Matrix3d& a, const Eigen::MatrixXd& x) {
  Eigen::MatrixXd y(x.rows(), x.cols());
  for (Eigen::Index f = 0; f < x.rows() / 3; ++f) y.middleRows<3>(3 * f) = a * x.middleRows<3>(3 * f);
  return y;
}

// The coordinates a body's ξ block eliminates: 3 n_f for a GCMS body, none for a floating-frame one.
Eigen::Index xi_count(const BodyModel& model) { return model.floating() ? 0 : 3 * model.field_count(); }

// J_b of a spring for body b: −P_1 if its first marker is on b, plus P_2 if its second is (3 x n_b; empty if the
// spring does not touch b).
Eigen::MatrixXd spring_jacobian(const SpringTangent& t, int body, Eigen::Index columns) {
  Eigen::MatrixXd j;
  if (t.first != body && t.second != body) return j;
  j = Eigen::MatrixXd::Zero(3, columns);
  if (t.first == body) j -= t.p_first;
  if (t.second == body) j += t.p_second;
  return j;
}

}  // namespace

DenseNewton::DenseNewton(const System& system, double beta_prime, double gamma_prime)
    : system_(system), beta_prime_(beta_prime), gamma_prime_(gamma_prime) {}

void DenseNewton::factor(double time, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& qdd,
                         const Eigen::VectorXd& mu, const Eigen::SparseMatrix<double>& sparse_jacobian) {
  const Eigen::MatrixXd jacobian(sparse_jacobian);
  const Eigen::Index n = q.size(), m = jacobian.rows();
  Eigen::MatrixXd& kkt = kkt_;
  kkt = Eigen::MatrixXd::Zero(n + m, n + m);
  kkt.topLeftCorner(n, n) = system_.mass_matrix(q) + (system_.stiffness(q) + system_.constraint_hessian(time, q, beta_prime_ * mu)) / beta_prime_;
  for (int b = 0; b < system_.body_count(); ++b) {  // a floating-frame body: (∂R/∂q + γ' ∂R/∂q̇)/β'
    if (!system_.model(b).floating()) continue;
    const FfrfTangent t = system_.floating_frame_tangent(b, q, v, qdd);
    const Eigen::Index o = system_.offset(b), n_b = t.stiffness.rows();
    kkt.block(o, o, n_b, n_b) += (t.stiffness + gamma_prime_ * t.damping) / beta_prime_;
  }
  for (const SpringTangent& t : system_.spring_tangents(q, v)) {  // Jᵀ (K + γ' C) J / β', every block
    const Eigen::Matrix3d k = (t.stiffness + gamma_prime_ * t.damping) / beta_prime_;
    for (int b = 0; b < system_.body_count(); ++b) {
      const Eigen::MatrixXd j_b = spring_jacobian(t, b, system_.model(b).coordinate_count());
      if (j_b.size() == 0) continue;
      for (int c = 0; c < system_.body_count(); ++c) {
        const Eigen::MatrixXd j_c = spring_jacobian(t, c, system_.model(c).coordinate_count());
        if (j_c.size() > 0) kkt.block(system_.offset(b), system_.offset(c), j_b.cols(), j_c.cols()) += j_b.transpose() * k * j_c;
      }
    }
  }
  for (int b = 0; b < system_.body_count(); ++b) {  // the damping's ξξ block Â D̂ Âᵀ, times γ'
    const BodyModel& model = system_.model(b);
    const bool sparse_damping = model.sparse && model.sparse->stiffness_damping > 0.0;
    if ((model.damping.size() == 0 && !sparse_damping) || model.floating()) continue;
    const Eigen::Index o = system_.offset(b) + 12, n_f = model.field_count();
    const Eigen::Matrix3d a = orientation_of(system_.body_coordinates(q, b));
    const Eigen::MatrixXd d = sparse_damping ? Eigen::MatrixXd(model.sparse->stiffness_damping * model.sparse->stiffness)
                                             : model.damping;
    for (Eigen::Index f = 0; f < n_f; ++f)
      for (Eigen::Index g = 0; g < n_f; ++g)
        kkt.block<3, 3>(o + 3 * f, o + 3 * g) += gamma_prime_ / beta_prime_ * a * d.block<3, 3>(3 * f, 3 * g) * a.transpose();
  }
  kkt.topRightCorner(n, m) = jacobian.transpose();
  kkt.bottomLeftCorner(m, n) = jacobian;
  lu_.compute(kkt);
}

void DenseNewton::solve(const Eigen::VectorXd&, const Eigen::VectorXd& residual, const Eigen::VectorXd& phi,
                        Eigen::VectorXd& dx) {
  Eigen::VectorXd rhs(residual.size() + phi.size());
  rhs << -residual, -phi;
  dx = lu_.solve(rhs);
}

ConstantCoreNewton::ConstantCoreNewton(const System& system, double beta_prime, double gamma_prime, bool sparse,
                                       CoreInverses& cores)
    : system_(system), beta_prime_(beta_prime), gamma_prime_(gamma_prime),
      inverses_(cores.get(system, beta_prime, gamma_prime)),
      reduced_(sparse ? std::unique_ptr<ReducedSolver>(std::make_unique<SparseReducedSolver>())
                      : std::make_unique<DenseReducedSolver>()) {
  for (int b = 0; b < system.body_count(); ++b) {
    const BodyModel& model = system.model(b);
    sparse_cores_.emplace_back();
    if (!model.sparse) continue;
    // The full-order body: C = M_s ⊗ I3 + K̄/β', factorized sparse (no damping).
    const Eigen::Index n_f = model.field_count();
    std::vector<Eigen::Triplet<double>> entries;
    const Eigen::SparseMatrix<double>& m_s = model.sparse->mass;
    for (Eigen::Index k = 0; k < m_s.outerSize(); ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(m_s, k); it; ++it)
        for (int d = 0; d < 3; ++d) entries.emplace_back(3 * it.row() + d, 3 * it.col() + d, it.value());
    Eigen::SparseMatrix<double> core(3 * n_f, 3 * n_f);
    core.setFromTriplets(entries.begin(), entries.end());
    core += (1.0 + gamma_prime * model.sparse->stiffness_damping) / beta_prime * model.sparse->stiffness;  // K̄ + γ' β K̄
    auto factor = std::make_unique<Eigen::SimplicialLLT<Eigen::SparseMatrix<double>>>(core);
    if (factor->info() != Eigen::Success)
      throw std::runtime_error("body '" + system.body_name(b) + "': the constant Newton core M_s x I3 + K_bar/beta' "
                               "is not positive definite");
    sparse_cores_.back() = std::move(factor);
  }
  eliminated_.resize(static_cast<std::size_t>(system.body_count()));
  for (int b = 0; b < system.body_count(); ++b) {
    const BodyModel& model = system.model(b);
    kept_offset_.push_back(kept_total_);
    kept_.push_back(model.floating() ? model.coordinate_count() : 12);
    kept_total_ += kept_.back();
  }
}

Eigen::MatrixXd ConstantCoreNewton::core_solve(int body, const Eigen::Matrix3d& a, const Eigen::MatrixXd& x) const {
  const auto k = static_cast<std::size_t>(body);
  if (sparse_cores_[k]) return rotate(a, sparse_cores_[k]->solve(rotate(a.transpose(), x)));
  const Eigen::MatrixXd rotated = rotate(a.transpose(), x);  // S_ff⁻¹ = Â C⁻¹ Âᵀ, column by column (factorization only)
  Eigen::MatrixXd y(rotated.rows(), rotated.cols());
  for (Eigen::Index c = 0; c < rotated.cols(); ++c) inverses_[k].multiply(rotated.col(c).data(), y.col(c).data());
  return rotate(a, y);
}

void ConstantCoreNewton::core_solve(int body, const Eigen::Matrix3d& a, const double* x, double* y) {
  // One right-hand side (every iteration): a matrix-vector product. The 3-blocks of x are the columns of a
  // 3 x n_f matrix, so Âᵀ x is Aᵀ X. The work vectors are the body's own (bodies run on several threads).
  const auto k = static_cast<std::size_t>(body);
  const Eigen::Index n_f = system_.model(body).field_count();
  Eliminated& e = eliminated_[k];
  e.rotated.resize(3 * n_f);
  e.core_y.resize(3 * n_f);
  Eigen::Map<Eigen::Matrix3Xd> rotated(e.rotated.data(), 3, n_f), core_y(e.core_y.data(), 3, n_f);
  rotated.noalias() = a.transpose() * Eigen::Map<const Eigen::Matrix3Xd>(x, 3, n_f);
  if (sparse_cores_[k])
    e.core_y = sparse_cores_[k]->solve(e.rotated);
  else
    inverses_[k].multiply(e.rotated.data(), e.core_y.data());
  Eigen::Map<Eigen::Matrix3Xd>(y, 3, n_f).noalias() = a * core_y;
}

struct ConstantCoreNewton::Coupling {
  const Eigen::SparseMatrix<double>& rate;                          ///< Z/γ' (m x n)
  const Eigen::SparseMatrix<double, Eigen::RowMajor>& direction;    ///< P = W Φ_q(q_f)ᵀ (n x m)
  const Eigen::SparseMatrix<double>& projected;                     ///< J P (m x m)
};

void ConstantCoreNewton::factor(double time, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& qdd,
                                const Eigen::VectorXd& mu, const Eigen::SparseMatrix<double>& jacobian) {
  // The joints' curvature ∂(Φ_qᵀ μ)/∂q (System::add_joint_hessian) is left out here: it is μ = λ/β' times the rows'
  // second derivatives, 1e-7 of this matrix on the bench's slider-crank at h = 2e-3 s, where it changed no iteration
  // count, while its differences cost 20 % of a step of the pendulum (fbsim, 8 modes, both formulations).
  // The dense reference matrix has it.
  static_cast<void>(time);
  assemble(q, v, qdd, mu, jacobian, nullptr);
}

void ConstantCoreNewton::factor_coupled(double time, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                        const Eigen::VectorXd& qdd, const Eigen::VectorXd& mu,
                                        const Eigen::SparseMatrix<double>& jacobian, const Eigen::SparseMatrix<double>& rate,
                                        const Eigen::SparseMatrix<double, Eigen::RowMajor>& direction,
                                        const Eigen::SparseMatrix<double>& projected) {
  static_cast<void>(time);
  const Coupling coupling{rate, direction, projected};
  assemble(q, v, qdd, mu, jacobian, &coupling);
}

void ConstantCoreNewton::assemble(const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& qdd,
                                  const Eigen::VectorXd& mu, const Eigen::SparseMatrix<double>& jacobian,
                                  const Coupling* coupling) {
  const int n_b = system_.body_count();
  const Eigen::Index m = jacobian.rows(), n_r = kept_total_;
  const Eigen::Index nu = n_r + m;  // where the coupled step's Δν columns and velocity rows start
  unknowns_ = coupling ? n_r + 2 * m : n_r + m;
  using Entries = std::vector<Eigen::Triplet<double>>;
  auto add_block = [](Entries& out, Eigen::Index row, Eigen::Index column, const Eigen::Ref<const Eigen::MatrixXd>& block) {
    for (Eigen::Index c = 0; c < block.cols(); ++c)
      for (Eigen::Index r = 0; r < block.rows(); ++r) out.emplace_back(row + r, column + c, block(r, c));
  };
  // Columns [o, o + count) of Φ_q as body b's kept coordinates (from r_b on) in the reduced matrix: J_r and J_rᵀ;
  // and of Z/γ' in the velocity rows of the coupled step.
  auto add_jacobian = [&](Entries& out, Eigen::Index o, Eigen::Index count, Eigen::Index r_b) {
    for (Eigen::Index c = 0; c < count; ++c) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(jacobian, o + c); it; ++it) {
        out.emplace_back(r_b + c, n_r + it.row(), it.value());
        out.emplace_back(n_r + it.row(), r_b + c, it.value());
      }
      if (coupling)
        for (Eigen::SparseMatrix<double>::InnerIterator it(coupling->rate, o + c); it; ++it)
          out.emplace_back(nu + it.row(), r_b + c, it.value());
    }
  };
  // The rows of a column-major matrix's columns [o, o + count) with a nonzero value (sorted), and those columns as a
  // dense |rows| x count block.
  auto rows_of = [](const Eigen::SparseMatrix<double>& a, Eigen::Index o, Eigen::Index count, std::vector<Eigen::Index>& rows,
                    Eigen::MatrixXd& block) {
    rows.clear();
    for (Eigen::Index c = 0; c < count; ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(a, o + c); it; ++it)
        if (it.value() != 0.0) rows.push_back(it.row());
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    block = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows.size()), count);
    for (Eigen::Index c = 0; c < count; ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(a, o + c); it; ++it)
        if (it.value() != 0.0) block(std::lower_bound(rows.begin(), rows.end(), it.row()) - rows.begin(), c) = it.value();
  };
  // The coupled step's P_b (body b's rows of P, over the ν columns `columns` that touch them), dense.
  auto direction_of = [&](Eigen::Index o, Eigen::Index count, std::vector<Eigen::Index>& columns) {
    columns.clear();
    for (Eigen::Index i = 0; i < count; ++i)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(coupling->direction, o + i); it; ++it)
        columns.push_back(it.col());
    std::sort(columns.begin(), columns.end());
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    Eigen::MatrixXd p_b = Eigen::MatrixXd::Zero(count, static_cast<Eigen::Index>(columns.size()));
    for (Eigen::Index i = 0; i < count; ++i)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(coupling->direction, o + i); it; ++it)
        p_b(i, std::lower_bound(columns.begin(), columns.end(), it.col()) - columns.begin()) = it.value();
    return p_b;
  };
  // The springs' tangents: their rigid-rigid blocks (within a body and between its two bodies) and, within a body,
  // the rigid-ξ coupling enter; their ξξ blocks cannot (the core is the body's constant).
  const std::vector<SpringTangent> springs = system_.spring_tangents(q, v);
  std::vector<std::vector<std::size_t>> springs_of(static_cast<std::size_t>(n_b));  // per body, the springs on it
  for (std::size_t s = 0; s < springs.size(); ++s) {
    if (springs[s].first != kGround) springs_of[static_cast<std::size_t>(springs[s].first)].push_back(s);
    if (springs[s].second != kGround && springs[s].second != springs[s].first)
      springs_of[static_cast<std::size_t>(springs[s].second)].push_back(s);
  }
  auto spring_k = [&](std::size_t s) -> Eigen::Matrix3d {
    return (springs[s].stiffness + gamma_prime_ * springs[s].damping) / beta_prime_;
  };
  // The reduced matrix in [Δq_r (12 per GCMS body, all of a floating-frame body); Δμ (; Δν)] after eliminating every
  // GCMS body's ξ: each body's own block, its Jacobian columns, and the fill its elimination leaves among the rows
  // that touch its ξ (its Tisserand rows and its joints').
  // Each body's part into its own list, on OpenMP's threads (detail::kParallelFrom); the lists are joined in body
  // order, so the matrix is the same for any thread count.
  body_entries_.resize(static_cast<std::size_t>(n_b));
  for_each(n_b, [&](int b) {
    const BodyModel& model = system_.model(b);
    const auto bs = static_cast<std::size_t>(b);
    const Eigen::Index r_b = kept_offset_[bs], o = system_.offset(b);
    Eliminated& e = eliminated_[bs];
    Entries& entries = body_entries_[bs];
    entries.clear();
    std::vector<Eigen::Index> touched;  // the ν columns of the body's rows of P
    e.rows.clear();
    e.cols.clear();
    if (model.floating()) {  // S_b = M(q) + (∂R/∂q + γ' ∂R/∂q̇ + 2 λ_p I_pp)/β', and its springs
      const Eigen::Index size = model.coordinate_count();
      const FfrfTangent t = system_.floating_frame_tangent(b, q, v, qdd);
      Eigen::MatrixXd s_b = t.mass + (t.stiffness + gamma_prime_ * t.damping) / beta_prime_;
      s_b.block<4, 4>(3, 3).diagonal().array() += 2.0 * mu(system_.reference_row(b));  // (2 λ/β') I, λ = β' μ
      for (const std::size_t s : springs_of[bs]) {
        const Eigen::MatrixXd j_b = spring_jacobian(springs[s], b, size);
        s_b += j_b.transpose() * spring_k(s) * j_b;
      }
      add_block(entries, r_b, r_b, s_b);
      add_jacobian(entries, o, size, r_b);
      if (coupling) {  // −M_b P_b
        const Eigen::MatrixXd mp = t.mass * direction_of(o, size, touched);
        for (Eigen::Index j = 0; j < mp.cols(); ++j)
          for (Eigen::Index i = 0; i < size; ++i) entries.emplace_back(r_b + i, nu + touched[static_cast<std::size_t>(j)], -mp(i, j));
      }
      return;
    }
    const Eigen::Index n_xi = 3 * model.field_count(), n_f = model.field_count();
    const VectorRef q_b = q.segment(o, 12 + n_xi);
    const Eigen::Matrix3d a = orientation_of(q_b);
    const VectorRef xi = q_b.tail(n_xi);
    // S_rr = G[0:4, 0:4] ⊗ I3 + (K_aa + H_aa) / β';  S_rf = G[0:4, 4:] ⊗ I3 + (K_aξ + H_aξ) / β'.
    Eigen::MatrixXd s_rr = Eigen::MatrixXd::Zero(12, 12), s_rf = Eigen::MatrixXd::Zero(12, n_xi);
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) s_rr.block<3, 3>(3 * r, 3 * c).diagonal().setConstant(model.g_border(r, c));
      for (Eigen::Index f = 0; f < n_f; ++f) s_rf.block<3, 3>(3 * r, 3 * f).diagonal().setConstant(model.g_border(r, 4 + f));
    }
    const Eigen::Index ref_rows = model.rigid() ? 6 : 9;  // rows with curvature (Eq. 77's rows are linear)
    Eigen::Matrix<double, 9, 1> lambda = Eigen::Matrix<double, 9, 1>::Zero();
    lambda.head(ref_rows) = beta_prime_ * mu.segment(system_.reference_row(b), ref_rows);
    const Eigen::Matrix<double, 9, Eigen::Dynamic> h = reference_hessian_a_rows(model.tisserand, xi, lambda);  // a rows
    s_rr.bottomRightCorner<9, 9>() += h.leftCols<9>() / beta_prime_;
    if (n_xi > 0) {
      const ElasticTangent t = body_elastic_tangent(model, a, xi, /*with_xi_xi=*/false);
      s_rr.bottomRightCorner<9, 9>() += t.aa / beta_prime_;
      s_rf.bottomRows<9>() += (t.a_xi + h.rightCols(n_xi)) / beta_prime_;
    }
    for (const std::size_t s : springs_of[bs]) {
      const Eigen::MatrixXd j_b = spring_jacobian(springs[s], b, 12 + n_xi);
      const Eigen::MatrixXd kj = spring_k(s) * j_b;
      s_rr += j_b.leftCols<12>().transpose() * kj.leftCols<12>();
      if (n_xi > 0) s_rf += j_b.leftCols<12>().transpose() * kj.rightCols(n_xi);
    }
    add_block(entries, r_b, r_b, s_rr);
    add_jacobian(entries, o, 12, r_b);
    Eigen::MatrixXd mp;  // the coupled step's M_b P_b ((G ⊗ I3) P_b, column by column)
    if (coupling) {
      const Eigen::MatrixXd p_b = direction_of(o, 12 + n_xi, touched);
      mp.resize(p_b.rows(), p_b.cols());
      for (Eigen::Index j = 0; j < p_b.cols(); ++j) mass_times(model, p_b.col(j), mp.col(j));
      for (Eigen::Index j = 0; j < mp.cols(); ++j)
        for (Eigen::Index i = 0; i < 12; ++i) entries.emplace_back(r_b + i, nu + touched[static_cast<std::size_t>(j)], -mp(i, j));
    }
    if (n_xi == 0) return;
    // Eliminate ξ: L = [S_rf; J_f (; Z_f/γ')] over the rows that involve this body's ξ (its reference rows and
    // joints), R = [S_fr, J_fᵀ (, −(M P)_f)].
    std::vector<Eigen::Index> constraint_rows, rate_rows;
    Eigen::MatrixXd j_f, z_f;
    rows_of(jacobian, o + 12, n_xi, constraint_rows, j_f);
    if (coupling) rows_of(coupling->rate, o + 12, n_xi, rate_rows, z_f);
    const auto k_rows = static_cast<Eigen::Index>(constraint_rows.size()), z_rows = z_f.rows();
    const Eigen::Index k_cols = coupling ? static_cast<Eigen::Index>(touched.size()) : 0;
    e.left.resize(12 + k_rows + z_rows, n_xi);
    e.left.topRows(12) = s_rf;
    e.left.middleRows(12, k_rows) = j_f;
    if (z_rows > 0) e.left.bottomRows(z_rows) = z_f;
    Eigen::MatrixXd right(n_xi, 12 + k_rows + k_cols);
    right.leftCols(12 + k_rows) = e.left.topRows(12 + k_rows).transpose();
    if (k_cols > 0) right.rightCols(k_cols) = -mp.bottomRows(n_xi);
    for (const Eigen::Index k : constraint_rows) {
      e.rows.push_back(n_r + k);
      e.cols.push_back(n_r + k);
    }
    for (const Eigen::Index k : rate_rows) e.rows.push_back(nu + k);
    if (coupling)
      for (const Eigen::Index k : touched) e.cols.push_back(nu + k);
    e.y = core_solve(b, a, right);
    e.left_kernel = PaddedMatrix(e.left);
    e.y_kernel = PaddedMatrix(e.y);
    const Eigen::MatrixXd schur = e.left * e.y;  // L S_ff⁻¹ R, subtracted
    auto reduced_index = [r_b](const std::vector<Eigen::Index>& others, Eigen::Index i) {
      return i < 12 ? r_b + i : others[static_cast<std::size_t>(i - 12)];
    };
    for (Eigen::Index c = 0; c < schur.cols(); ++c)
      for (Eigen::Index r = 0; r < schur.rows(); ++r)
        entries.emplace_back(reduced_index(e.rows, r), reduced_index(e.cols, c), -schur(r, c));
  });
  entries_.clear();
  for (const Entries& part : body_entries_) entries_.insert(entries_.end(), part.begin(), part.end());
  for (std::size_t s = 0; s < springs.size(); ++s) {  // a spring between two bodies: their rigid-rigid blocks
    const int b = springs[s].first, c = springs[s].second;
    if (b == kGround || c == kGround || b == c) continue;
    const auto bs = static_cast<std::size_t>(b), cs = static_cast<std::size_t>(c);
    const Eigen::MatrixXd j_b = spring_jacobian(springs[s], b, system_.model(b).coordinate_count()).leftCols(kept_[bs]);
    const Eigen::MatrixXd j_c = spring_jacobian(springs[s], c, system_.model(c).coordinate_count()).leftCols(kept_[cs]);
    const Eigen::Matrix3d k = spring_k(s);
    add_block(entries_, kept_offset_[bs], kept_offset_[cs], j_b.transpose() * k * j_c);
    add_block(entries_, kept_offset_[cs], kept_offset_[bs], j_c.transpose() * k * j_b);
  }
  if (coupling)  // the velocity rows' −J P
    for (Eigen::Index k = 0; k < coupling->projected.outerSize(); ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(coupling->projected, k); it; ++it)
        entries_.emplace_back(nu + it.row(), nu + it.col(), -it.value());
  reduced_->factor(unknowns_, entries_);
}

void ConstantCoreNewton::solve(const Eigen::VectorXd& q, const Eigen::VectorXd& residual, const Eigen::VectorXd& phi,
                               Eigen::VectorXd& dx) {
  const Eigen::Index m = phi.size();
  rhs_.resize(unknowns_);
  rhs_.tail(m) = -phi;
  dx.resize(q.size() + m);
  solve_reduced(q, residual, dx);
}

void ConstantCoreNewton::solve_coupled(const Eigen::VectorXd& q, const Eigen::VectorXd& residual, const Eigen::VectorXd& phi,
                                       const Eigen::VectorXd& velocity_rows, Eigen::VectorXd& dx) {
  const Eigen::Index m = phi.size();
  rhs_.resize(unknowns_);
  rhs_.segment(kept_total_, m) = -phi;
  rhs_.tail(m) = phi - velocity_rows;
  dx.resize(q.size() + 2 * m);
  solve_reduced(q, residual, dx);
}

void ConstantCoreNewton::solve_reduced(const Eigen::VectorXd& q, const Eigen::VectorXd& residual, Eigen::VectorXd& dx) {
  const int n_b = system_.body_count();
  const Eigen::Index n_r = kept_total_, extra = unknowns_ - n_r;
  // Per body (in parallel: each its own work vectors) S_ff⁻¹ r_f at the current A (the core is exact for any A; only
  // the coupling blocks are from the factorization) and L S_ff⁻¹ r_f; then their sums into the shared rows, in body
  // order.
  for_each(n_b, [&](int b) {
    const Eigen::Index o = system_.offset(b), n_xi = xi_count(system_.model(b));
    const Eigen::Index r_b = kept_offset_[static_cast<std::size_t>(b)], k_b = kept_[static_cast<std::size_t>(b)];
    rhs_.segment(r_b, k_b) = -residual.segment(o, k_b);
    if (n_xi == 0) return;
    Eliminated& e = eliminated_[static_cast<std::size_t>(b)];
    e.residual_solution.resize(n_xi);
    core_solve(b, orientation_of(q.segment(o, 12)), residual.data() + o + 12, e.residual_solution.data());
    e.coupled.resize(e.left.rows());  // per body: its size differs between bodies
    e.left_kernel.multiply(e.residual_solution.data(), e.coupled.data());  // L S_ff⁻¹ r_f
  });
  for (int b = 0; b < n_b; ++b) {
    if (xi_count(system_.model(b)) == 0) continue;
    const Eliminated& e = eliminated_[static_cast<std::size_t>(b)];
    rhs_.segment(kept_offset_[static_cast<std::size_t>(b)], 12) += e.coupled.head<12>();
    for (std::size_t i = 0; i < e.rows.size(); ++i) rhs_(e.rows[i]) += e.coupled(12 + static_cast<Eigen::Index>(i));
  }
  reduced_->solve(rhs_, reduced_solution_);
  const Eigen::VectorXd& x = reduced_solution_;
  // Back-substitute: Δq_f = −S_ff⁻¹ (r_f + R [Δq_r; x(cols)]), each body into its own rows.
  dx.tail(extra) = x.tail(extra);
  for_each(n_b, [&](int b) {
    const Eigen::Index o = system_.offset(b), n_xi = xi_count(system_.model(b));
    const Eigen::Index r_b = kept_offset_[static_cast<std::size_t>(b)], k_b = kept_[static_cast<std::size_t>(b)];
    dx.segment(o, k_b) = x.segment(r_b, k_b);
    if (n_xi == 0) return;
    Eliminated& e = eliminated_[static_cast<std::size_t>(b)];
    const auto k_cols = static_cast<Eigen::Index>(e.cols.size());
    e.unknowns.resize(12 + k_cols);
    e.unknowns.head<12>() = x.segment(r_b, 12);
    for (Eigen::Index i = 0; i < k_cols; ++i) e.unknowns(12 + i) = x(e.cols[static_cast<std::size_t>(i)]);
    e.y_kernel.multiply(e.unknowns.data(), dx.data() + o + 12);
    dx.segment(o + 12, n_xi) = -(dx.segment(o + 12, n_xi) + e.residual_solution);
  });
}

}  // namespace flexbody::runtime::detail
