#include "flexbody/preprocess/eigensolver.hpp"

#include <arpack.hpp>

#include <Spectra/SymGEigsShiftSolver.h>
#include <fmt/format.h>

#include "block_lanczos.hpp"

#ifdef FLEXBODY_WITH_SLEPC
#include "slepc_shift_solve.hpp"
#endif

#include <algorithm>
#include <numeric>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace flexbody::preprocess {
namespace {

}  // namespace

int lanczos_basis_size(int nev, Eigen::Index n) {
  // The deflated operator has rank n - 6: a larger basis would only hold round-off.
  return static_cast<int>(std::min<Eigen::Index>(n - 6, std::max(2 * nev + 1, nev + 20)));
}

namespace {

// A reproducible start vector inside the deflated space: P (random).
Eigen::VectorXd start_vector(ShiftSolve& op, const VectorMassOperator& mass) {
  const Eigen::Index n = op.rows();
  std::mt19937_64 generator(20230131);  // fixed seed: identical runs give identical modes
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd x(n), mx(n), y(n);
  for (Eigen::Index i = 0; i < n; ++i) x(i) = uniform(generator);
  mass.perform_op(x.data(), mx.data());
  op.perform_op(mx.data(), y.data());  // one shift-invert step: in range of the deflated operator
  return y / y.norm();
}

void sort_ascending(EigenPairs& pairs) {
  std::vector<Eigen::Index> order(pairs.eigenvalues.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](Eigen::Index a, Eigen::Index b) { return pairs.eigenvalues(a) < pairs.eigenvalues(b); });
  EigenPairs sorted = pairs;
  for (std::size_t k = 0; k < order.size(); ++k) {
    sorted.eigenvalues(static_cast<Eigen::Index>(k)) = pairs.eigenvalues(order[k]);
    sorted.vectors.col(static_cast<Eigen::Index>(k)) = pairs.vectors.col(order[k]);
  }
  pairs = std::move(sorted);
}

// ARPACK's dseupd recounts the converged Ritz values from dsaupd's estimates and stops with
// info = -17 if its count differs from dsaupd's (seen with arpack-ng 3.8 before the rigid-body
// deflation, when extra Ritz values near zero converged too).
constexpr a_int kSeupdCountMismatch = -17;

// nullopt if dseupd reports kSeupdCountMismatch.
std::optional<EigenPairs> solve_arpack(ShiftSolve& op, const VectorMassOperator& mass, int nev,
                                       double tolerance, const EigensolverOptions& options) {
  const auto n = static_cast<a_int>(op.rows());
  const a_int ncv = lanczos_basis_size(nev, n);
  const a_int lworkl = ncv * (ncv + 8);
  Eigen::VectorXd resid = start_vector(op, mass);
  std::vector<double> v(static_cast<std::size_t>(n) * ncv), workd(3 * static_cast<std::size_t>(n)), workl(lworkl);
  std::vector<double> mx(n);
  a_int iparam[11] = {}, ipntr[11] = {};
  iparam[0] = 1;                    // exact shifts
  iparam[2] = options.max_restarts;  // maximum number of restarts
  iparam[6] = 3;                    // mode 3: shift-invert, OP = (K - sigma M)^-1 M, B = M
  a_int ido = 0, info = 1;          // info = 1: use resid as the start vector
  EigenPairs result;
  while (true) {
    arpack::saupd(ido, arpack::bmat::generalized, n, arpack::which::largest_magnitude, nev, tolerance,
                  resid.data(), ncv, v.data(), n, iparam, ipntr, workd.data(), workl.data(), lworkl, info);
    double* in = workd.data() + ipntr[0] - 1;
    double* out = workd.data() + ipntr[1] - 1;
    if (ido == -1) {  // y = OP x without M x at hand
      mass.perform_op(in, mx.data());
      op.perform_op(mx.data(), out);
      ++result.operator_applies;
    } else if (ido == 1) {  // y = OP x with M x in workd(ipntr(3))
      op.perform_op(workd.data() + ipntr[2] - 1, out);
      ++result.operator_applies;
    } else if (ido == 2) {  // y = M x
      mass.perform_op(in, out);
    } else {
      break;
    }
  }
  if (info == 1) throw std::runtime_error("ARPACK: no convergence after " + std::to_string(iparam[2]) +
                                          " restarts (" + std::to_string(iparam[4]) + " of " +
                                          std::to_string(nev) + " eigenpairs converged)");
  if (info != 0) throw std::runtime_error("ARPACK dsaupd failed with info = " + std::to_string(info));
  result.iterations = iparam[2];

  std::vector<a_int> select(ncv, 1);
  result.eigenvalues.resize(nev);
  result.vectors.resize(n, nev);
  arpack::seupd(/*rvec=*/1, arpack::howmny::ritz_vectors, select.data(), result.eigenvalues.data(),
                result.vectors.data(), n, op.shift(), arpack::bmat::generalized, n, arpack::which::largest_magnitude,
                nev, tolerance, resid.data(), ncv, v.data(), n, iparam, ipntr, workd.data(), workl.data(),
                lworkl, info);
  if (info == kSeupdCountMismatch) return std::nullopt;
  if (info != 0) throw std::runtime_error("ARPACK dseupd failed with info = " + std::to_string(info));
  sort_ascending(result);
  return result;
}

// Spectra calls set_shift itself (again) and then uses our operator; our set_shift refactorizes only
// when the shift changes.
struct SpectraShiftSolve {
  using Scalar = double;
  ShiftSolve& op;
  [[nodiscard]] Eigen::Index rows() const { return op.rows(); }
  [[nodiscard]] Eigen::Index cols() const { return op.rows(); }
  void set_shift(double sigma) {
    if (sigma != op.shift()) op.set_shift(sigma);
  }
  void perform_op(const double* x, double* y) { op.perform_op(x, y); }
};

EigenPairs solve_spectra(ShiftSolve& op, const VectorMassOperator& mass, int nev,
                         const EigensolverOptions& options) {
  SpectraShiftSolve shift_solve{op};
  VectorMassOperator mass_op = mass;  // Spectra takes the B operator by non-const reference
  const int ncv = lanczos_basis_size(nev, op.rows());
  Spectra::SymGEigsShiftSolver<SpectraShiftSolve, VectorMassOperator, Spectra::GEigsMode::ShiftInvert> solver(
      shift_solve, mass_op, nev, ncv, op.shift());
  solver.init(start_vector(op, mass).data());
  const double tolerance = options.tolerance > 0.0 ? options.tolerance : 1e-15;
  const Eigen::Index converged =
      solver.compute(Spectra::SortRule::LargestMagn, options.max_restarts, tolerance, Spectra::SortRule::SmallestAlge);
  if (solver.info() != Spectra::CompInfo::Successful || converged < nev)
    throw std::runtime_error("Spectra: no convergence after " + std::to_string(solver.num_iterations()) +
                             " restarts (" + std::to_string(converged) + " of " + std::to_string(nev) +
                             " eigenpairs converged)");
  EigenPairs result;
  result.eigenvalues = solver.eigenvalues();
  result.vectors = solver.eigenvectors();
  result.iterations = static_cast<int>(solver.num_iterations());
  result.operator_applies = static_cast<int>(solver.num_operations());
  sort_ascending(result);
  return result;
}

}  // namespace

std::string_view to_string(EigensolverBackend backend) {
  switch (backend) {
    case EigensolverBackend::automatic: return "auto";
    case EigensolverBackend::arpack: return "arpack";
    case EigensolverBackend::spectra: return "spectra";
    case EigensolverBackend::block_lanczos: return "block-lanczos";
    case EigensolverBackend::slepc: return "slepc";
  }
  return "unknown";
}

EigensolverBackend resolve_backend(EigensolverBackend backend, Eigen::Index dofs, int nev, Eigen::Index block_size) {
  if (backend != EigensolverBackend::automatic) return backend;
  const bool fits = block_size >= 1 && block_lanczos_basis_limit(nev, block_size, dofs) >= 10 * static_cast<Eigen::Index>(nev);
  return dofs >= kBlockLanczosFromDofs && fits ? EigensolverBackend::block_lanczos : EigensolverBackend::arpack;
}

bool slepc_available() {
#ifdef FLEXBODY_WITH_SLEPC
  return true;
#else
  return false;
#endif
}

EigensolverBackend eigensolver_backend_from_string(std::string_view text) {
  if (text == "auto") return EigensolverBackend::automatic;
  if (text == "arpack") return EigensolverBackend::arpack;
  if (text == "spectra") return EigensolverBackend::spectra;
  if (text == "block-lanczos") return EigensolverBackend::block_lanczos;
  if (text == "slepc") {
    if (!slepc_available())
      throw std::invalid_argument("eigensolver: 'slepc' is not in this build (configure with -DFLEXBODY_WITH_SLEPC=ON)");
    return EigensolverBackend::slepc;
  }
  throw std::invalid_argument("eigensolver: '" + std::string(text) + "' is unknown; use auto, arpack, spectra, block-lanczos or slepc");
}

std::unique_ptr<ShiftSolve> make_shift_solve(EigensolverBackend backend, const SparseMatrix& stiffness_upper,
                                             const SparseMatrix& scalar_mass_upper, Eigen::MatrixXd deflation) {
  if (backend == EigensolverBackend::slepc) {
#ifdef FLEXBODY_WITH_SLEPC
    return std::make_unique<SlepcShiftSolve>(stiffness_upper, scalar_mass_upper, std::move(deflation));
#else
    throw std::invalid_argument("eigensolver: 'slepc' is not in this build (configure with -DFLEXBODY_WITH_SLEPC=ON)");
#endif
  }
  // Under mpirun this runs on rank 0 alone (fbprep's command line refuses that combination as a waste of ranks).
  return std::make_unique<CholmodShiftSolve>(stiffness_upper, scalar_mass_upper, std::move(deflation));
}

EigenPairs solve_shift_invert(ShiftSolve& op, const VectorMassOperator& mass, int nev,
                              const EigensolverOptions& options) {
  const Eigen::Index n = op.rows();
  if (nev < 1 || nev > n - 8)
    throw std::invalid_argument("eigensolver: the number of modes must satisfy 1 <= nev <= " +
                                std::to_string(n - 8) + " (DOFs - 6 rigid-body modes - 2), got " + std::to_string(nev));
  const EigensolverBackend backend = resolve_backend(options.backend, n, nev, options.block_size);
  if (backend == EigensolverBackend::slepc) {
#ifdef FLEXBODY_WITH_SLEPC
    auto* distributed = dynamic_cast<SlepcShiftSolve*>(&op);
    if (distributed == nullptr) throw std::logic_error("eigensolver slepc: the operator is not from make_shift_solve(slepc)");
    EigenPairs pairs = distributed->eigenpairs(mass, nev, options);
    pairs.backend = EigensolverBackend::slepc;
    return pairs;
#else
    throw std::invalid_argument("eigensolver: 'slepc' is not in this build (configure with -DFLEXBODY_WITH_SLEPC=ON)");
#endif
  }
  if (backend == EigensolverBackend::spectra) {
    EigenPairs pairs = solve_spectra(op, mass, nev, options);
    pairs.backend = EigensolverBackend::spectra;
    return pairs;
  }
  if (backend == EigensolverBackend::block_lanczos) {
    try {
      EigenPairs pairs = solve_block_lanczos(op, mass, nev, options);
      pairs.backend = EigensolverBackend::block_lanczos;
      return pairs;
    } catch (const std::runtime_error&) {
      // Not converged within its basis, or the Krylov space exhausted: auto goes on with ARPACK, which restarts
      // (the solves so far stay in op.stats()); a backend asked for by name reports its failure.
      if (options.backend != EigensolverBackend::automatic) throw;
    }
  }
  const int solves_before = op.stats().solves;
  if (std::optional<EigenPairs> pairs = solve_arpack(op, mass, nev, options.tolerance, options)) return *pairs;
  if (options.tolerance == 0.0) throw std::runtime_error("ARPACK dseupd: converged-count mismatch (info = -17)");
  // dseupd miscounted at tol > 0. At tol = 0 (machine precision) unwanted Ritz values practically
  // never pass the convergence test, so the counts agree; the retry costs ~1.8x the solves.
  std::optional<EigenPairs> pairs = solve_arpack(op, mass, nev, 0.0, options);
  if (!pairs) throw std::runtime_error("ARPACK dseupd: converged-count mismatch (info = -17) even at tol = 0");
  pairs->operator_applies = op.stats().solves - solves_before;
  return *pairs;
}

}  // namespace flexbody::preprocess
