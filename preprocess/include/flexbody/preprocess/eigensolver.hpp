#pragma once
// flexbody/preprocess/eigensolver.hpp: the generalized symmetric eigenproblem K̄ phi = lambda M̄ phi,
// lowest eigenvalues above a shift, by shift-invert Lanczos (ARPACK or Spectra on one process) or by SLEPc's
// Krylov-Schur on a MUMPS factorization distributed over MPI ranks (builds with -DFLEXBODY_WITH_SLEPC=ON).

#include "flexbody/preprocess/shift_invert_operator.hpp"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <string_view>

namespace flexbody::preprocess {

enum class EigensolverBackend { arpack, spectra, slepc };
[[nodiscard]] std::string_view to_string(EigensolverBackend backend);
/// "arpack", "spectra" or "slepc"; throws std::invalid_argument otherwise, and for "slepc" in a build
/// without it.
[[nodiscard]] EigensolverBackend eigensolver_backend_from_string(std::string_view text);
/// True when this build has the SLEPc backend (-DFLEXBODY_WITH_SLEPC=ON).
[[nodiscard]] bool slepc_available();

struct EigensolverOptions {
  EigensolverBackend backend = EigensolverBackend::arpack;
  /// Relative accuracy of the Ritz values of the shift-inverted operator (ARPACK's and Spectra's tol).
  /// Measured on the bracket at 17k-127k DOFs: 1e-14 ... 1e-10 all converge after 69 solves with the
  /// same relative residuals ||K phi - lambda M phi|| / ||K phi|| (3e-11 ... 2e-10, the rounding floor),
  /// while 0 (machine precision) needs 120-122 solves for the same residuals. slepc runs at 1e-2 times this
  /// (its vectors at 1e-12 sit further from converged; slepc_shift_solve.cpp gives the figures).
  double tolerance = 1e-12;
  int max_restarts = 1000;
};

/// Eigenpairs with lambda ascending; vectors M̄-orthonormal (3 n_n x nev).
struct EigenPairs {
  Eigen::VectorXd eigenvalues;
  Eigen::MatrixXd vectors;
  int iterations = 0;      ///< restarts of the implicitly restarted Lanczos method
  int operator_applies = 0;
};

/// Lanczos basis size used for nev eigenpairs of an operator of dimension n (deflated rank n - 6):
/// min(n - 6, max(2 nev + 1, nev + 20)) vectors of n doubles.
[[nodiscard]] int lanczos_basis_size(int nev, Eigen::Index n);

/// The shift-solve operator a backend works on: CHOLMOD for arpack and spectra, the distributed MUMPS
/// factorization for slepc (collective over the MPI ranks, see parallel_session.hpp). K and M_s are borrowed.
[[nodiscard]] std::unique_ptr<ShiftSolve> make_shift_solve(EigensolverBackend backend, const SparseMatrix& stiffness_upper,
                                                           const SparseMatrix& scalar_mass_upper,
                                                           Eigen::MatrixXd deflation);

/// The `nev` eigenvalues nearest to (and above) sigma of K̄ phi = lambda M̄ phi within the range of
/// the deflated operator. `op` must already be factorized at `sigma` (set_shift) and come from
/// make_shift_solve for the same backend. Throws std::runtime_error if the backend fails or does not converge.
[[nodiscard]] EigenPairs solve_shift_invert(ShiftSolve& op, const VectorMassOperator& mass, int nev,
                                            const EigensolverOptions& options);

}  // namespace flexbody::preprocess
