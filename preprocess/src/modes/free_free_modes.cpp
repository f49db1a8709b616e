#include "flexbody/preprocess/free_free_modes.hpp"

#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/eigen_residual.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"

#include "frequency.hpp"
#include "lanczos_basis_limit.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace flexbody::preprocess {
namespace {

// Elastic eigenvalues below this fraction of the reference bar's (2 pi f_ref)^2 are zero-energy modes:
// a real part is 1e5 times less stiff than a bar only as a mechanism (f below 1e-5 f_ref, i.e. below
// 0.03 Hz for a 1 m steel part, where a real first mode is tens of Hz or more).
constexpr double kZeroEnergyFraction = 1e-10;
using detail::kMaxLanczosBasisBytes;
// K̄ r for the six rigid-body fields cancels terms of size ||K|| ||r||; more than this is an assembly error.
constexpr double kMaxRigidBodyResidual = 1e-10;

double reference_frequency(const RowMatrixX3d& nodes, const Material& material) {
  const double diagonal = (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).norm();
  return std::sqrt(material.youngs_modulus / material.density) / (2.0 * diagonal);
}

// ||K||_1 (= ||K||_inf) of the symmetric matrix from its upper triangle, without forming it.
double one_norm(const SparseMatrix& upper) {
  Eigen::VectorXd column_sums = Eigen::VectorXd::Zero(upper.cols());
  for (Eigen::Index j = 0; j < upper.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(upper, j); it; ++it) {
      column_sums(j) += std::abs(it.value());
      if (it.row() != j) column_sums(it.row()) += std::abs(it.value());
    }
  return column_sums.maxCoeff();
}

}  // namespace

double automatic_shift(const RowMatrixX3d& nodes, const Material& material) {
  const double f_shift = reference_frequency(nodes, material) / 20.0;
  return -(kTwoPi * f_shift) * (kTwoPi * f_shift);
}

Eigen::MatrixXd upsilon_from_modes(const Eigen::MatrixXd& modes) {
  const Eigen::Index n_nodes = modes.rows() / 3;
  Eigen::MatrixXd upsilon(n_nodes, 3 * modes.cols());
  for (Eigen::Index m = 0; m < modes.cols(); ++m)
    for (Eigen::Index i = 0; i < n_nodes; ++i)
      for (int k = 0; k < 3; ++k) upsilon(i, 3 * m + k) = modes(3 * i + k, m);
  return upsilon;
}

FreeFreeModes free_free_modes(const RowMatrixX3d& nodes, const SparseMatrix& stiffness_upper,
                              const SparseMatrix& scalar_mass_upper, const Material& material,
                              const FreeFreeOptions& options, const Eigen::MatrixXd& static_loads,
                              const Eigen::MatrixXd& prestress_loads, const std::vector<std::string>& prestress_names) {
  if (options.modes < 0) throw std::invalid_argument(fmt::format("modes: must be >= 0, got {}", options.modes));
  if (options.fmax_hz < 0.0 || !std::isfinite(options.fmax_hz))
    throw std::invalid_argument(fmt::format("fmax: must be a positive frequency, got {}", options.fmax_hz));
  if (options.shift > 0.0 || !std::isfinite(options.shift))
    throw std::invalid_argument(fmt::format("shift: must be negative, got {}", options.shift));
  const Eigen::Index n = stiffness_upper.rows();
  const int available = static_cast<int>(n - 6 - 2);  // the solvers need nev < ncv <= n - 6
  if (available < 1) throw std::invalid_argument("free-free modes: the mesh has too few nodes");
  // Largest nev whose Lanczos basis (about 2 nev + 1 vectors of n doubles) fits in kMaxLanczosBasisBytes.
  const auto affordable =
      static_cast<int>(std::max<long>(1, (static_cast<long>(kMaxLanczosBasisBytes / (8.0 * n)) - 1) / 2));
  const int limit = std::min(available, affordable);
  if (options.modes > limit)
    throw std::invalid_argument(fmt::format(
        "--modes {}: at most {} modes for this mesh ({})", options.modes, limit,
        limit == available
            ? fmt::format("{} DOFs less the 6 rigid-body modes and 2", n)
            : fmt::format("their Lanczos basis would exceed {:.0f} GiB", kMaxLanczosBasisBytes / (1ull << 30))));

  FreeFreeModes result;
  const Eigen::MatrixXd rigid = rigid_body_modes(nodes, scalar_mass_upper);
  {  // K must annihilate the rigid fields; this also checks the assembly.
    const double k_norm = one_norm(stiffness_upper);
    Eigen::VectorXd kr(n);
    for (int k = 0; k < 6; ++k) {
      apply_symmetric(stiffness_upper, rigid.col(k), kr);
      result.rigid_body_residual = std::max(result.rigid_body_residual, kr.norm() / (k_norm * rigid.col(k).norm()));
    }
    if (!(result.rigid_body_residual <= kMaxRigidBodyResidual))
      throw std::logic_error(fmt::format("free-free modes: the stiffness does not annihilate the rigid-body fields "
                                         "(||K r|| / (||K|| ||r||) = {:.3g}): an assembly error",
                                         result.rigid_body_residual));
  }
  result.shift = options.shift < 0.0 ? options.shift : automatic_shift(nodes, material);
  const std::unique_ptr<ShiftSolve> solver =
      make_shift_solve(options.solver.backend, stiffness_upper, scalar_mass_upper, rigid);
  ShiftSolve& op = *solver;
  op.set_shift(result.shift);
  const VectorMassOperator mass(scalar_mass_upper);

  int nev = std::min(options.modes > 0 ? options.modes : 12, limit);
  EigenPairs pairs;
  while (true) {
    if (options.progress) options.progress(fmt::format("eigensolver: {} modes by {}", nev,
                                                     to_string(resolve_backend(options.solver.backend, n, nev,
                                                                               options.solver.block_size))));
    pairs = solve_shift_invert(op, mass, nev, options.solver);
    ++result.solver_runs;
    result.restarts += pairs.iterations;
    result.operator_applies += pairs.operator_applies;
    result.eigensolver = pairs.backend;
    const double f_top = std::sqrt(std::max(pairs.eigenvalues(nev - 1), 0.0)) / kTwoPi;
    const bool enough_for_fmax = options.fmax_hz <= 0.0 || f_top > options.fmax_hz;
    const bool capped = options.modes > 0 && nev >= options.modes;
    if (enough_for_fmax || capped) break;
    if (nev >= limit)
      throw std::invalid_argument(fmt::format(
          "--fmax {}: more than {} modes lie below it (the {}th is at {:.6g} Hz); lower --fmax or cap with --modes",
          options.fmax_hz, nev, nev, f_top));
    nev = std::min(2 * nev, limit);
  }

  const double zero_energy = kZeroEnergyFraction * std::pow(kTwoPi * reference_frequency(nodes, material), 2);
  int zero_modes = 0;
  for (Eigen::Index k = 0; k < pairs.eigenvalues.size(); ++k) zero_modes += pairs.eigenvalues(k) < zero_energy;
  if (zero_modes > 0)
    throw std::runtime_error(fmt::format(
        "free-free modes: {} zero-energy modes beyond the 6 rigid-body modes (lowest {:.3g} Hz): the mesh "
        "has a mechanism (parts joined only at an edge or a node) or is not one connected solid",
        zero_modes, std::sqrt(std::max(pairs.eigenvalues(0), 0.0)) / kTwoPi));

  Eigen::Index keep = pairs.eigenvalues.size();
  if (options.fmax_hz > 0.0) {
    keep = 0;
    while (keep < pairs.eigenvalues.size() && std::sqrt(pairs.eigenvalues(keep)) / kTwoPi <= options.fmax_hz) ++keep;
  }
  if (options.modes > 0) keep = std::min<Eigen::Index>(keep, options.modes);
  if (keep == 0)
    throw std::runtime_error(fmt::format("free-free modes: no elastic mode at or below fmax = {} Hz (the first is "
                                         "{:.6g} Hz)", options.fmax_hz, std::sqrt(pairs.eigenvalues(0)) / kTwoPi));
  result.normal_modes = keep;
  result.eigenvalues = pairs.eigenvalues.head(keep);
  result.vectors = pairs.vectors.leftCols(keep);
  if (static_loads.cols() > 0) {
    if (static_loads.rows() != n) throw std::invalid_argument("free-free modes: the static loads have the wrong length");
    if (options.progress) options.progress(fmt::format("static correction: {} unit loads", static_loads.cols()));
    Eigen::MatrixXd known(n, 6 + keep);
    known << rigid, result.vectors;
    StaticCorrectionModes correction =
        static_correction_modes(op, stiffness_upper, scalar_mass_upper, known, static_loads);
    result.static_correction = correction.stats;
    result.vectors.conservativeResize(n, keep + correction.vectors.cols());
    result.vectors.rightCols(correction.vectors.cols()) = correction.vectors;
    result.eigenvalues.conservativeResize(result.vectors.cols());
    result.eigenvalues.tail(correction.eigenvalues.size()) = correction.eigenvalues;
  }
  if (prestress_loads.cols() > 0) {
    if (prestress_loads.rows() != n) throw std::invalid_argument("free-free modes: the prestress loads have the wrong length");
    if (options.progress) options.progress(fmt::format("prestress: {} unit load cases", prestress_loads.cols()));
    result.prestress_responses =
        relieved_static_responses(op, stiffness_upper, scalar_mass_upper, rigid, prestress_loads, result.prestress,
                                  prestress_names, "geometric stiffness");
  }
  const Eigen::Index n_m = result.vectors.cols();
  result.frequencies_hz = result.eigenvalues.cwiseMax(0.0).cwiseSqrt() / kTwoPi;
  result.relative_residuals.resize(n_m);
  result.residual_floors.resize(n_m);
  // One pass over K̄ per mode, the modes on all threads (at 1M DOFs a pass takes about 0.3 s, 26 of them 8 s serially).
  double coupling = 0.0;
#pragma omp parallel reduction(max : coupling)
  {
    Eigen::VectorXd mphi(n);
#pragma omp for schedule(dynamic)
    for (Eigen::Index k = 0; k < n_m; ++k) {
      const EigenResidual residual =
          eigen_residual(stiffness_upper, scalar_mass_upper, result.eigenvalues(k), result.vectors.col(k));
      result.relative_residuals(k) = residual.relative;
      result.residual_floors(k) = residual.floor;
      mass.perform_op(result.vectors.col(k).data(), mphi.data());
      coupling = std::max(coupling, (rigid.transpose() * mphi).cwiseAbs().maxCoeff());
    }
  }
  result.rigid_body_coupling = coupling;
  result.stats = op.stats();
  // Each normal mode against its own rounding floor (eigen_residual.hpp).
  const Eigen::Index worst = worst_refused(result.relative_residuals.head(keep), result.residual_floors.head(keep));
  if (worst >= 0)
    throw std::runtime_error(
        fmt::format("free-free modes: mode {} ({:.6g} Hz) is not converged: {}", worst + 1, result.frequencies_hz(worst),
                    describe_refusal(result.relative_residuals(worst), result.residual_floors(worst))));
  return result;
}

}  // namespace flexbody::preprocess
