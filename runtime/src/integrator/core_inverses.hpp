#pragma once
// core_inverses.hpp (private): the inverse of each reduced body's constant Newton core,
//
//   C = G_ff ⊗ I3 + (K̂ + γ' D̂) / β'   (formulations.md, "The Method": the constant core; β', γ' of the step size h),
//
// kept for the last few step sizes. A change of h needs new cores, and building them (an LLT and an inverse, both
// O((3 n_f)³), of each distinct part) costs as much as several steps: on the work-precision pendulum at 32 modes
// (3 n_f = 288) 3.3 ms against 0.3-0.4 ms per step. Error control returns to step sizes taken before (a row
// interval split into k equal steps, k rising and falling with the motion), and so do a failed step's halves.

#include "flexbody/runtime/system.hpp"

#include "../kernels/dense_product.hpp"

#include <cstddef>
#include <vector>

namespace flexbody::runtime::detail {

class CoreInverses {
 public:
  /// Per body, C⁻¹ at (β', γ'): computed, or the one computed before for bitwise-equal β' and γ' (the same numbers
  /// either way). Empty for rigid, floating-frame and full-order bodies (whose sparse core ConstantCoreNewton
  /// factorizes itself). Bodies with bitwise-equal cores share one matrix. Throws std::runtime_error naming a body
  /// whose core is not positive definite.
  [[nodiscard]] std::vector<PaddedMatrix> get(const System& system, double beta_prime, double gamma_prime);
  /// Step sizes kept; the least recently used is dropped first. The memory is (3 n_f)² doubles per distinct part and
  /// size (26 MB at 3 n_f = 1 800): sizes beyond kKeptBytes in all are dropped too (at 3 n_f = 6 000, 288 MB a size,
  /// only the one in use is kept), but the size just asked for is always kept.
  static constexpr std::size_t kKept = 8;
  static constexpr std::size_t kKeptBytes = std::size_t{256} << 20;
  [[nodiscard]] long built() const { return built_; }  ///< cores computed so far (not taken from those kept)

 private:
  struct Kept {
    double beta_prime, gamma_prime;
    std::vector<PaddedMatrix> inverses;
    long used;          ///< when it was last asked for (the count of get()s)
    std::size_t bytes;  ///< of the distinct matrices in `inverses`
  };
  std::vector<Kept> kept_;
  long asked_ = 0, built_ = 0;
};

}  // namespace flexbody::runtime::detail
