#include "core_inverses.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace flexbody::runtime::detail {
namespace {

std::vector<PaddedMatrix> compute(const System& system, double beta_prime, double gamma_prime) {
  std::vector<PaddedMatrix> inverses(static_cast<std::size_t>(system.body_count()));
  SharedMatrices shared;  // copies of one part share one C⁻¹ (equal cores give bitwise-equal inverses)
  for (int b = 0; b < system.body_count(); ++b) {
    const BodyModel& model = system.model(b);
    if (model.sparse || model.floating() || model.field_count() == 0) continue;
    const Eigen::Index n_f = model.field_count();
    // C = G_ff ⊗ I3 + (K̂ + γ' D̂) / β' (formulations.md, "The Method": the constant core).
    Eigen::MatrixXd core = model.stiffness / beta_prime;
    if (model.damping.size() > 0) core += gamma_prime / beta_prime * model.damping;
    for (Eigen::Index f = 0; f < n_f; ++f)
      for (Eigen::Index g = 0; g < n_f; ++g) core.block<3, 3>(3 * f, 3 * g).diagonal().array() += model.mass_matrix(4 + f, 4 + g);
    const Eigen::LLT<Eigen::MatrixXd> factor(core);
    if (factor.info() != Eigen::Success)
      throw std::runtime_error("body '" + system.body_name(b) + "': the constant Newton core G_ff x I3 + "
                               "(K_hat + gamma' D_hat)/beta' is not positive definite");
    // C⁻¹ explicitly: one matrix-vector product per solve instead of two triangular solves, which Eigen runs
    // several times slower (measured: bench/README.md). C is symmetric positive definite and well conditioned
    // (G_ff = I for a body file's M_s-orthonormal fields, so cond C ≤ 1 + λ_max(K̂ + γ'D̂)/β', with λ_max(K̂) the
    // stiffest shape of the 3 n_f-dimensional field space, above the kept modes' ω²), so the inverse loses only
    // about cond(C)·ε.
    inverses[static_cast<std::size_t>(b)] = shared.get(factor.solve(Eigen::MatrixXd::Identity(3 * n_f, 3 * n_f)));
  }
  return inverses;
}

}  // namespace

std::vector<PaddedMatrix> CoreInverses::get(const System& system, double beta_prime, double gamma_prime) {
  ++asked_;
  for (Kept& k : kept_)
    if (k.beta_prime == beta_prime && k.gamma_prime == gamma_prime) {
      k.used = asked_;
      return k.inverses;
    }
  std::vector<PaddedMatrix> inverses = compute(system, beta_prime, gamma_prime);
  ++built_;
  std::vector<const double*> distinct;
  std::size_t bytes = 0;
  for (const PaddedMatrix& c : inverses)
    if (c.rows() > 0 && std::find(distinct.begin(), distinct.end(), c.storage()) == distinct.end()) {
      distinct.push_back(c.storage());
      bytes += sizeof(double) * static_cast<std::size_t>(c.rows() * c.cols());
    }
  auto total = [&] {
    std::size_t sum = 0;
    for (const Kept& k : kept_) sum += k.bytes;
    return sum;
  };
  while (!kept_.empty() && (kept_.size() >= kKept || total() + bytes > kKeptBytes))
    kept_.erase(std::min_element(kept_.begin(), kept_.end(), [](const Kept& a, const Kept& b) { return a.used < b.used; }));
  kept_.push_back({beta_prime, gamma_prime, inverses, asked_, bytes});
  return inverses;
}

}  // namespace flexbody::runtime::detail
