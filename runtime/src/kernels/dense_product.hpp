#pragma once
// dense_product.hpp (internal): y = A x for the runtime's per-iteration dense matrices, K̂ ξ̄ (Eq. 87) and
// C⁻¹ r (FORMULATION.md section 5), both 3 n_f square.
//
// Eigen picks its vector width when it is compiled: a portable build (no -march) runs these products with SSE2,
// two doubles per instruction. This kernel is compiled for several instruction sets and the dynamic loader picks
// the widest the machine has (GCC's target_clones), so a distribution build gets AVX2 or AVX-512 where they exist.
// Measured on this project's machine at 3 n_f = 180 (bench/README.md, "runtime_bench"): Eigen 5.7-9 µs in the
// portable build, 3.3 µs with -march=native; this kernel 3.0-3.5 µs in either.

#include <Eigen/Core>

namespace flexbody::runtime::detail {

/// y = A x. x and y hold a.cols() and a.rows() doubles and must not overlap each other or A.
void dense_product(const Eigen::MatrixXd& a, const double* x, double* y);

}  // namespace flexbody::runtime::detail
