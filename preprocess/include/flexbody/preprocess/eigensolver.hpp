#pragma once
// flexbody/preprocess/eigensolver.hpp: the generalized symmetric eigenproblem K̄ phi = lambda M̄ phi,
// lowest eigenvalues above a shift, by shift-invert Lanczos (ARPACK or Spectra).

#include "flexbody/preprocess/shift_invert_operator.hpp"

#include <Eigen/Core>

#include <string>
#include <string_view>

namespace flexbody::preprocess {

enum class EigensolverBackend { arpack, spectra };
[[nodiscard]] std::string_view to_string(EigensolverBackend backend);
/// "arpack" or "spectra"; throws std::invalid_argument otherwise.
[[nodiscard]] EigensolverBackend eigensolver_backend_from_string(std::string_view text);

struct EigensolverOptions {
  EigensolverBackend backend = EigensolverBackend::arpack;
  /// Relative accuracy of the Ritz values of the shift-inverted operator (ARPACK's and Spectra's tol).
  /// Measured on the bracket at 17k-127k DOFs: 1e-14 ... 1e-10 all converge after 69 solves with the
  /// same relative residuals ||K phi - lambda M phi|| / ||K phi|| (3e-11 ... 2e-10, the rounding floor),
  /// while 0 (machine precision) needs 120-122 solves for the same residuals.
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

/// The `nev` eigenvalues nearest to (and above) sigma of K̄ phi = lambda M̄ phi within the range of
/// the deflated operator. `op` must already be factorized at `sigma` (set_shift). Throws
/// std::runtime_error if the backend fails or does not converge.
[[nodiscard]] EigenPairs solve_shift_invert(CholmodShiftSolve& op, const VectorMassOperator& mass, int nev,
                                            const EigensolverOptions& options);

}  // namespace flexbody::preprocess
