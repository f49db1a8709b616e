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

/// automatic: block_lanczos on eigenproblems of kBlockLanczosFromDofs DOFs or more whose basis fits, arpack otherwise
/// and if block Lanczos fails (resolve_backend, solve_shift_invert).
enum class EigensolverBackend { automatic, arpack, spectra, block_lanczos, slepc };
[[nodiscard]] std::string_view to_string(EigensolverBackend backend);
/// "auto", "arpack", "spectra", "block-lanczos" or "slepc"; throws std::invalid_argument otherwise, and for "slepc" in a build
/// without it.
[[nodiscard]] EigensolverBackend eigensolver_backend_from_string(std::string_view text);
/// Where `automatic` switches from arpack to block_lanczos (DOFs of the eigenproblem). Measured on the bracket, 26
/// modes (bench/README.md, "Block Lanczos"): the eigen stage takes as long at 43k DOFs, 12 % less at 58k, 24 % at
/// 79k, 15 % at 127k and 203k; its Krylov basis takes 1.4 GB at 1.05M DOFs against ARPACK's 0.45.
inline constexpr Eigen::Index kBlockLanczosFromDofs = 50'000;
/// The backend `backend` stands for on an eigenproblem of `dofs` DOFs and `nev` modes: itself, unless it is automatic;
/// then block_lanczos from kBlockLanczosFromDofs DOFs if its basis limit allows 10 vectors per mode (it needed 6.5
/// on the bracket), arpack otherwise.
[[nodiscard]] EigensolverBackend resolve_backend(EigensolverBackend backend, Eigen::Index dofs, int nev,
                                                 Eigen::Index block_size = 8);
/// True when this build has the SLEPc backend (-DFLEXBODY_WITH_SLEPC=ON).
[[nodiscard]] bool slepc_available();

struct EigensolverOptions {
  EigensolverBackend backend = EigensolverBackend::automatic;
  /// Relative accuracy of the Ritz values of the shift-inverted operator (ARPACK's and Spectra's tol).
  /// Measured on the bracket at 17k-127k DOFs: 1e-14 ... 1e-10 all converge after 69 solves with the
  /// same relative residuals ||K phi - lambda M phi|| / ||K phi|| (3e-11 ... 2e-10, the rounding floor),
  /// while 0 (machine precision) needs 120-122 solves for the same residuals. slepc runs at 1e-2 times this
  /// (its vectors at 1e-12 sit further from converged; slepc_shift_solve.cpp gives the figures).
  double tolerance = 1e-12;
  int max_restarts = 1000;
  /// Right-hand sides per solve of the block-lanczos backend (measured at 1.05M DOFs: bench/README.md).
  Eigen::Index block_size = 8;
};

/// Eigenpairs with lambda ascending; vectors M̄-orthonormal (3 n_n x nev).
struct EigenPairs {
  Eigen::VectorXd eigenvalues;
  Eigen::MatrixXd vectors;
  int iterations = 0;      ///< restarts of the implicitly restarted Lanczos method (block steps of block Lanczos)
  int operator_applies = 0;
  EigensolverBackend backend = EigensolverBackend::arpack;  ///< the one that delivered them (never automatic)
};

/// Lanczos basis size used for nev eigenpairs of an operator of dimension n (deflated rank n - 6):
/// min(n - 6, max(2 nev + 1, nev + 20)) vectors of n doubles.
[[nodiscard]] int lanczos_basis_size(int nev, Eigen::Index n);

/// Largest Krylov basis the block-lanczos backend may build for nev eigenpairs in blocks of b (a multiple of b):
/// 20 nev rounded up to whole blocks, at least 8 blocks, at most the deflated rank n - 6 and at most 4 GiB of basis
/// (ARPACK's limit too).
[[nodiscard]] Eigen::Index block_lanczos_basis_limit(int nev, Eigen::Index block, Eigen::Index n);

/// The shift-solve operator a backend works on: CHOLMOD for arpack and spectra, the distributed MUMPS
/// factorization for slepc (collective over the MPI ranks, see parallel_session.hpp). K and M_s are borrowed.
[[nodiscard]] std::unique_ptr<ShiftSolve> make_shift_solve(EigensolverBackend backend, const SparseMatrix& stiffness_upper,
                                                           const SparseMatrix& scalar_mass_upper,
                                                           Eigen::MatrixXd deflation);

/// The `nev` eigenvalues nearest to (and above) sigma of K̄ phi = lambda M̄ phi within the range of
/// the deflated operator. `op` must already be factorized at `sigma` (set_shift) and come from
/// make_shift_solve for the same backend. Throws std::runtime_error if the backend fails or does not converge;
/// with `automatic`, a block Lanczos that fails is followed by ARPACK on the same factorization.
[[nodiscard]] EigenPairs solve_shift_invert(ShiftSolve& op, const VectorMassOperator& mass, int nev,
                                            const EigensolverOptions& options);

}  // namespace flexbody::preprocess
