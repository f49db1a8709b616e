#pragma once
// lanczos_basis_limit.hpp (internal): the memory a Lanczos basis may take, ARPACK's (free_free_modes.cpp) and block
// Lanczos's (block_lanczos.cpp) alike; the factor and the matrices come on top of it.

namespace flexbody::preprocess::detail {

/// The largest Lanczos basis, n x ncv doubles [bytes]: 4 GiB.
inline constexpr double kMaxLanczosBasisBytes = 4.0 * (1ull << 30);

}  // namespace flexbody::preprocess::detail
