#pragma once
// block_lanczos.hpp (internal): the block-lanczos eigensolver backend, a shift-invert block Lanczos method with
// full reorthogonalization on the BLAS. It exists for large meshes, whose solves are bound by reading the factor:
// one pass over CHOLMOD's factor solves for b right-hand sides at little more than the cost of one
// (bench/README.md, "Block Lanczos"), so b-vector blocks make up for the larger Krylov basis a block method needs.

#include "flexbody/preprocess/eigensolver.hpp"

namespace flexbody::preprocess {

/// The nev eigenpairs of K̄ phi = lambda M̄ phi nearest above op's shift, by block Lanczos on
/// OP = P (K̄ - sigma M̄)^-1 M̄ in the M̄ inner product; vectors M̄-orthonormal, lambda ascending. Converged when
/// every wanted Ritz pair (theta, y) of OP has ||OP y - theta y||_M̄ <= 1e-2 options.tolerance theta (ARPACK's test
/// at a hundredth of its tolerance; 1e-2 eps for tolerance 0). Throws std::invalid_argument if the basis limit
/// (block_lanczos_basis_limit) leaves no room for nev vectors and a block, std::runtime_error if it is reached
/// before convergence or the Krylov space is exhausted.
[[nodiscard]] EigenPairs solve_block_lanczos(ShiftSolve& op, const VectorMassOperator& mass, int nev,
                                             const EigensolverOptions& options);

}  // namespace flexbody::preprocess
