// The constant Newton cores kept per step size (runtime/src/integrator/core_inverses.hpp): a step size taken before
// computes nothing, its inverses are the same numbers as computed afresh, and the least recently used size is dropped.
#include "integrator/core_inverses.hpp"

#include "mechanism_helpers.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace fr = flexbody::runtime;

namespace {

// β' and γ' for step h as the Newmark rule gives them (β = 0.3, γ = 0.6); the cores need only two positive numbers
// per step size.
double beta_prime(double h) { return 1.0 / (0.3 * h * h); }
double gamma_prime(double h) { return 0.6 / (0.3 * h); }

// C⁻¹ x for each body's kept inverse (empty for bodies without one).
std::vector<Eigen::VectorXd> applied(const std::vector<fr::detail::PaddedMatrix>& inverses) {
  std::vector<Eigen::VectorXd> out;
  for (const fr::detail::PaddedMatrix& c : inverses) {
    out.emplace_back();
    if (c.rows() == 0) continue;
    const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(c.cols(), -1.0, 2.0);
    out.back().resize(c.rows());
    c.multiply(x.data(), out.back().data());
  }
  return out;
}

}  // namespace

TEST(CoreInverses, AStepSizeTakenBeforeComputesNothingAndGivesTheSameNumbers) {
  const auto system = mechanisms::chain(6);  // rigid, GCMS and FFRF bodies in turn: two GCMS bodies of one part
  fr::detail::CoreInverses cores;
  const double h = 1e-3;
  const std::vector<fr::detail::PaddedMatrix> first = cores.get(*system, beta_prime(h), gamma_prime(h));
  ASSERT_EQ(first.size(), 6U);
  int reduced = 0;
  for (int b = 0; b < 6; ++b) {
    const bool gcms = b % 3 == 1;  // chain(): body k is rigid, GCMS, FFRF for k % 3 = 0, 1, 2
    EXPECT_EQ(first[static_cast<std::size_t>(b)].rows() > 0, gcms) << "body " << b;
    reduced += gcms ? 1 : 0;
  }
  EXPECT_EQ(reduced, 2);
  EXPECT_EQ(first[1].storage(), first[4].storage());  // copies of one part share one inverse
  EXPECT_EQ(cores.built(), 1);

  const std::vector<fr::detail::PaddedMatrix> again = cores.get(*system, beta_prime(h), gamma_prime(h));
  EXPECT_EQ(cores.built(), 1);
  EXPECT_EQ(again[1].storage(), first[1].storage());

  // kKept other sizes: h is the least recently used and is dropped; asked again, it is computed again, bit for bit.
  for (std::size_t k = 1; k <= fr::detail::CoreInverses::kKept; ++k) {
    const double other = h * (1.0 + 0.1 * static_cast<double>(k));
    (void)cores.get(*system, beta_prime(other), gamma_prime(other));
  }
  EXPECT_EQ(cores.built(), 1 + static_cast<long>(fr::detail::CoreInverses::kKept));
  const std::vector<fr::detail::PaddedMatrix> recomputed = cores.get(*system, beta_prime(h), gamma_prime(h));
  EXPECT_EQ(cores.built(), 2 + static_cast<long>(fr::detail::CoreInverses::kKept));
  EXPECT_NE(recomputed[1].storage(), first[1].storage());
  const std::vector<Eigen::VectorXd> a = applied(first), b = applied(recomputed);
  ASSERT_EQ(a[1].size(), b[1].size());
  EXPECT_EQ(std::memcmp(a[1].data(), b[1].data(), sizeof(double) * static_cast<std::size_t>(a[1].size())), 0);

  // The most recent sizes are still kept: the last of the loop computes nothing.
  const double last = h * (1.0 + 0.1 * static_cast<double>(fr::detail::CoreInverses::kKept));
  (void)cores.get(*system, beta_prime(last), gamma_prime(last));
  EXPECT_EQ(cores.built(), 2 + static_cast<long>(fr::detail::CoreInverses::kKept));
}
