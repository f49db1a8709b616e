#include "flexbody/preprocess/craig_bampton.hpp"

#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/eigen_residual.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"

#include "../linalg/skew.hpp"
#include "frequency.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace flexbody::preprocess {
namespace {

// The submatrix of an upper-triangle CSC matrix on the rows and columns with new_index >= 0 (new_index
// increasing with the old index, so the result is upper and sorted too).
SparseMatrix upper_submatrix(const SparseMatrix& upper, const std::vector<std::int64_t>& new_index, Eigen::Index size) {
  std::vector<Eigen::Triplet<double, std::int64_t>> entries;
  entries.reserve(static_cast<std::size_t>(upper.nonZeros()));
  for (Eigen::Index c = 0; c < upper.outerSize(); ++c) {
    if (new_index[c] < 0) continue;
    for (SparseMatrix::InnerIterator it(upper, c); it; ++it)
      if (new_index[it.row()] >= 0) entries.emplace_back(new_index[it.row()], new_index[c], it.value());
  }
  SparseMatrix sub(size, size);
  sub.setFromTriplets(entries.begin(), entries.end());
  sub.makeCompressed();
  return sub;
}

using detail::skew;

}  // namespace

CraigBamptonModes craig_bampton_modes(const RowMatrixX3d& nodes, const SparseMatrix& stiffness_upper,
                                      const SparseMatrix& scalar_mass_upper, const Material& material,
                                      const std::vector<RigidInterface>& interfaces,
                                      const CraigBamptonOptions& options, const Eigen::MatrixXd& static_loads) {
  const Eigen::Index n_n = nodes.rows(), n = 3 * n_n;
  if (interfaces.empty())
    throw std::invalid_argument("craig-bampton: at least one rbe2 interface is needed (its constraint modes)");
  if (options.fixed_interface_modes < 0 || (options.fixed_interface_modes == 0 && !(options.fmax_hz > 0.0)))
    throw std::invalid_argument(fmt::format("craig-bampton: give modes >= 1 or fmax > 0 (modes {}, fmax {})",
                                            options.fixed_interface_modes, options.fmax_hz));
  if (options.fmax_hz < 0.0 || !std::isfinite(options.fmax_hz))
    throw std::invalid_argument(fmt::format("craig-bampton: fmax must be a positive frequency, got {}", options.fmax_hz));

  // Interior (free) nodes and DOFs: every node not tied to an interface.
  std::vector<char> boundary(static_cast<std::size_t>(n_n), 0);
  for (const RigidInterface& i : interfaces)
    for (Eigen::Index k = 0; k < i.nodes.size(); ++k) boundary[i.nodes(k)] = 1;
  std::vector<std::int64_t> node_index(static_cast<std::size_t>(n_n), -1), dof_index(static_cast<std::size_t>(n), -1);
  Eigen::Index n_interior = 0;
  for (Eigen::Index i = 0; i < n_n; ++i)
    if (!boundary[i]) {
      node_index[i] = n_interior;
      for (int c = 0; c < 3; ++c) dof_index[3 * i + c] = 3 * n_interior + c;
      ++n_interior;
    }
  // The solvers need nev < ncv <= n, and the Lanczos basis (about 2 nev + 1 vectors) must fit in 4 GiB, as
  // for free-free modes.
  const double basis_bytes = 4.0 * (1ull << 30);
  const int affordable = static_cast<int>(std::max<long>(1, (static_cast<long>(basis_bytes / (8.0 * 3.0 * static_cast<double>(n_interior))) - 1) / 2));
  const int limit = std::min(static_cast<int>(3 * n_interior) - 8, affordable);
  if (options.fixed_interface_modes > limit || limit < 1)
    throw std::invalid_argument(fmt::format("craig-bampton: {} fixed-interface modes need more than the {} interior "
                                            "DOFs", options.fixed_interface_modes, 3 * n_interior));
  const SparseMatrix k_ii = upper_submatrix(stiffness_upper, dof_index, 3 * n_interior);
  const SparseMatrix m_ii = upper_submatrix(scalar_mass_upper, node_index, n_interior);

  // 1. Fixed-interface modes: K_ii φ = ω² M_ii φ, positive definite (the interfaces hold the body).
  CraigBamptonModes result;
  if (options.shift > 0.0 || !std::isfinite(options.shift))
    throw std::invalid_argument(fmt::format("craig-bampton: shift must be negative, got {}", options.shift));
  result.shift = options.shift < 0.0 ? options.shift : automatic_shift(nodes, material);
  const std::unique_ptr<ShiftSolve> solver =
      make_shift_solve(options.solver.backend, k_ii, m_ii, Eigen::MatrixXd(3 * n_interior, 0));
  ShiftSolve& op = *solver;
  op.set_shift(result.shift);
  const VectorMassOperator mass_ii(m_ii);
  // With fmax: solve for more modes until the last one lies above it, then keep those at or below.
  int nev = options.fixed_interface_modes > 0 ? options.fixed_interface_modes : std::min(12, limit);
  EigenPairs fixed = solve_shift_invert(op, mass_ii, nev, options.solver);
  if (options.fmax_hz > 0.0) {
    auto top_hz = [&] { return std::sqrt(std::max(fixed.eigenvalues(nev - 1), 0.0)) / kTwoPi; };
    while (options.fixed_interface_modes == 0 && top_hz() <= options.fmax_hz) {
      if (nev >= limit)
        throw std::invalid_argument(fmt::format("craig-bampton: more than {} fixed-interface modes lie below fmax = {} Hz; "
                                                "lower fmax or cap with modes", nev, options.fmax_hz));
      nev = std::min(2 * nev, limit);
      fixed = solve_shift_invert(op, mass_ii, nev, options.solver);
    }
    int keep = 0;
    while (keep < nev && std::sqrt(std::max(fixed.eigenvalues(keep), 0.0)) / kTwoPi <= options.fmax_hz) ++keep;
    if (keep == 0)
      throw std::invalid_argument(fmt::format("craig-bampton: no fixed-interface mode at or below fmax = {} Hz (the "
                                              "first is {:.6g} Hz)", options.fmax_hz,
                                              std::sqrt(std::max(fixed.eigenvalues(0), 0.0)) / kTwoPi));
    nev = keep;
    fixed.eigenvalues.conservativeResize(keep);
    fixed.vectors.conservativeResize(Eigen::NoChange, keep);
  }
  result.fixed_interface_eigenvalues = fixed.eigenvalues;
  result.fixed_interface_frequencies_hz = fixed.eigenvalues.cwiseMax(0.0).cwiseSqrt() / kTwoPi;
  result.fixed_interface_residuals.resize(nev);
  result.fixed_interface_residual_floors.resize(nev);
#pragma omp parallel for schedule(dynamic)  // one pass over K_ii per mode, the modes on all threads
  for (int m = 0; m < nev; ++m) {
    const EigenResidual residual = eigen_residual(k_ii, m_ii, fixed.eigenvalues(m), fixed.vectors.col(m));
    result.fixed_interface_residuals(m) = residual.relative;
    result.fixed_interface_residual_floors(m) = residual.floor;
  }
  // These are eigenpairs of the clamped problem, judged as free-free modes are: each against its own floor.
  const Eigen::Index worst = worst_refused(result.fixed_interface_residuals, result.fixed_interface_residual_floors);
  if (worst >= 0)
    throw std::runtime_error(fmt::format("craig-bampton: fixed-interface mode {} ({:.6g} Hz) is not converged: {}",
                                         worst + 1, result.fixed_interface_frequencies_hz(worst),
                                         describe_refusal(result.fixed_interface_residuals(worst),
                                                          result.fixed_interface_residual_floors(worst))));

  // 2. Constraint modes: unit rigid motions of one interface, the others clamped, the interior in
  // static equilibrium: x_i = -K_ii^-1 K_ib u_b.
  op.set_shift(0.0);
  const Eigen::Index n_c = 6 * static_cast<Eigen::Index>(interfaces.size());
  result.basis = Eigen::MatrixXd::Zero(n, nev + n_c);
  for (int m = 0; m < nev; ++m)
    for (Eigen::Index d = 0; d < n; ++d)
      if (dof_index[d] >= 0) result.basis(d, m) = fixed.vectors(dof_index[d], m);
  Eigen::VectorXd u(n), ku(n), rhs(3 * n_interior), x(3 * n_interior);
  for (std::size_t j = 0; j < interfaces.size(); ++j)
    for (int k = 0; k < 6; ++k) {
      u.setZero();
      const RigidInterface& face = interfaces[j];
      for (Eigen::Index a = 0; a < face.nodes.size(); ++a) {
        const Eigen::Index i = face.nodes(a);
        const Eigen::Vector3d d = nodes.row(i).transpose() - face.reference_point;
        // Translation e_k, or the small rotation e_(k-3) x d.
        u.segment<3>(3 * i) = k < 3 ? Eigen::Vector3d(Eigen::Vector3d::Unit(k)) : Eigen::Vector3d(-skew(d).col(k - 3));
      }
      apply_symmetric(stiffness_upper, u, ku);
      for (Eigen::Index d = 0; d < n; ++d)
        if (dof_index[d] >= 0) rhs(dof_index[d]) = -ku(d);
      op.perform_op(rhs.data(), x.data());
      for (Eigen::Index d = 0; d < n; ++d)
        if (dof_index[d] >= 0) u(d) = x(dof_index[d]);
      result.basis.col(nev + 6 * static_cast<Eigen::Index>(j) + k) = u;
    }

  // 3. Static corrections: the clamped body's responses to the loads, less what the fixed-interface modes
  // hold (the same factor of K_ii solves them; the loads' shares on interface nodes go into the ties).
  if (static_loads.cols() > 0) {
    if (static_loads.rows() != n) throw std::invalid_argument("craig-bampton: the static loads have the wrong length");
    Eigen::MatrixXd interior_loads(3 * n_interior, static_loads.cols());
    for (Eigen::Index d = 0; d < n; ++d)
      if (dof_index[d] >= 0) interior_loads.row(dof_index[d]) = static_loads.row(d);
    const StaticCorrectionModes correction = static_correction_modes(op, k_ii, m_ii, fixed.vectors, interior_loads);
    result.static_correction = correction.stats;
    const Eigen::Index n_s = correction.vectors.cols(), first = result.basis.cols();
    result.basis.conservativeResize(n, first + n_s);
    result.basis.rightCols(n_s).setZero();
    for (Eigen::Index d = 0; d < n; ++d)
      if (dof_index[d] >= 0) result.basis.row(d).tail(n_s) = correction.vectors.row(dof_index[d]);
  }
  result.stats = op.stats();
  result.eigensolver = fixed.backend;

  // 4. Orthonormalise: the reduced eigenproblem on the basis (Eqs. of a Rayleigh-Ritz step).
  const Eigen::Index m_b = result.basis.cols();
  Eigen::MatrixXd k_basis(n, m_b), m_basis(n, m_b);
  for (Eigen::Index c = 0; c < m_b; ++c) {
    apply_symmetric(stiffness_upper, result.basis.col(c), k_basis.col(c));
    apply_vector_mass(scalar_mass_upper, result.basis.col(c), m_basis.col(c));
  }
  Eigen::MatrixXd k_r = result.basis.transpose() * k_basis, m_r = result.basis.transpose() * m_basis;
  k_r = 0.5 * (k_r + k_r.transpose()).eval();
  m_r = 0.5 * (m_r + m_r.transpose()).eval();
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> reduced(k_r, m_r);
  if (reduced.info() != Eigen::Success)
    throw std::runtime_error("craig-bampton: the reduced eigenproblem failed (dependent basis vectors?)");
  // Zero-energy vectors: below 1e-10 of the body's reference frequency squared, as for free-free modes.
  const double f_ref = std::sqrt(material.youngs_modulus / material.density) /
                       (2.0 * (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).norm());
  const double zero_energy = 1e-10 * std::pow(kTwoPi * f_ref, 2);
  // The six rigid motions lie in the basis exactly; they are told from the elastic vectors by the gap
  // (relative, so independent of how the basis vectors are scaled), and the 7th must have real energy.
  const Eigen::VectorXd& lambda = reduced.eigenvalues();
  if (m_b < 7 || !(std::abs(lambda(5)) <= 1e-6 * lambda(6)) || !(lambda(6) > zero_energy))
    throw std::runtime_error(fmt::format("craig-bampton: the reduced model does not have exactly 6 zero-energy vectors "
                                         "(6th and 7th eigenvalues {:.3g} and {:.3g} rad^2/s^2): a mechanism in the "
                                         "part?", m_b > 5 ? lambda(5) : 0.0, m_b > 6 ? lambda(6) : 0.0));
  const Eigen::Index n_e = m_b - 6;
  Eigen::MatrixXd modes = result.basis * reduced.eigenvectors().rightCols(n_e);
  // Exactly free of rigid motion (the translational Tisserand constraint then holds identically):
  // project with the closed-form rigid fields and M̄-orthonormalise again (a change at round-off level).
  const Eigen::MatrixXd r = rigid_body_modes(nodes, scalar_mass_upper);
  Eigen::MatrixXd m_modes(n, n_e), m_rigid(n, 6);
  for (int c = 0; c < 6; ++c) apply_vector_mass(scalar_mass_upper, r.col(c), m_rigid.col(c));
  modes -= r * (m_rigid.transpose() * modes);
  for (Eigen::Index c = 0; c < n_e; ++c) apply_vector_mass(scalar_mass_upper, modes.col(c), m_modes.col(c));
  const Eigen::MatrixXd gram = modes.transpose() * m_modes;
  const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (gram + gram.transpose()));
  if (llt.info() != Eigen::Success) throw std::runtime_error("craig-bampton: the orthonormalised modes are dependent");
  Eigen::MatrixXd w = llt.matrixU().solve<Eigen::OnTheRight>(modes);  // W U^-1: M̄-orthonormal
  // A last Rayleigh-Ritz step on W, so that the eigenvalues belong to these very vectors (the projection
  // and re-orthonormalisation moved them at round-off level).
  Eigen::MatrixXd k_w(n, n_e);
  for (Eigen::Index c = 0; c < n_e; ++c) apply_symmetric(stiffness_upper, w.col(c), k_w.col(c));
  Eigen::MatrixXd h = w.transpose() * k_w;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(0.5 * (h + h.transpose()));
  result.vectors = w * ritz.eigenvectors();
  result.eigenvalues = ritz.eigenvalues();
  result.frequencies_hz = result.eigenvalues.cwiseMax(0.0).cwiseSqrt() / kTwoPi;
  result.rigid_body_coupling = (m_rigid.transpose() * result.vectors).cwiseAbs().maxCoeff();
  // Residuals in the tied model (the rbe2 patches rigid): nodal forces on interior DOFs, and on each
  // interface the resultant force and moment about its reference point. The untied residual would be
  // dominated by the tie's reactions, which are forces of the constraint, not errors.
  auto in_tied_model = [&](const Eigen::VectorXd& full) {
    Eigen::VectorXd tied(3 * n_interior + n_c);
    for (Eigen::Index d = 0; d < n; ++d)
      if (dof_index[d] >= 0) tied(dof_index[d]) = full(d);
    for (std::size_t j = 0; j < interfaces.size(); ++j) {
      Eigen::Vector3d force = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
      for (Eigen::Index a = 0; a < interfaces[j].nodes.size(); ++a) {
        const Eigen::Index i = interfaces[j].nodes(a);
        const Eigen::Vector3d f = full.segment<3>(3 * i);
        force += f;
        moment += (nodes.row(i).transpose() - interfaces[j].reference_point).cross(f);
      }
      tied.segment<3>(3 * n_interior + 6 * static_cast<Eigen::Index>(j)) = force;
      tied.segment<3>(3 * n_interior + 6 * static_cast<Eigen::Index>(j) + 3) = moment;
    }
    return tied;
  };
  result.relative_residuals.resize(n_e);
  const Eigen::MatrixXd k_vectors = k_w * ritz.eigenvectors();
  Eigen::VectorXd mv(n);
  for (Eigen::Index c = 0; c < n_e; ++c) {
    const Eigen::VectorXd kv = k_vectors.col(c);
    apply_vector_mass(scalar_mass_upper, result.vectors.col(c), mv);
    result.relative_residuals(c) =
        in_tied_model(kv - result.eigenvalues(c) * mv).norm() / in_tied_model(kv).norm();
  }
  return result;
}

}  // namespace flexbody::preprocess
