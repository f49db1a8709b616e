// The sparse Newton solve of scenes of many bodies (issue 27): the constant core's reduced matrix factorized by KLU
// against its dense inverse and against the dense reference Newton matrix, on random mechanisms (open trees and
// closed loops, every joint type, GCMS, FFRF and rigid bodies); a chain's trajectory with either; and the symbolic
// analysis done once per pattern.
#include "integrator/newton_solvers.hpp"

#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"
#include "flexbody/runtime/threads.hpp"
#include "mechanism_helpers.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <optional>
#include <random>

namespace fr = flexbody::runtime;

using namespace mechanisms;

TEST(SparseNewton, SolvesAgreeWithTheDenseOnesOnRandomMechanisms) {
  int tried = 0, closed = 0;
  for (unsigned seed = 1; tried < 12 && seed < 100; ++seed) {
    const bool loops = seed % 2 == 0;
    const auto system = random_mechanism(seed, 4 + static_cast<int>(seed % 5), loops ? 3 : 0);
    const Eigen::VectorXd q0 = system->initial_coordinates();
    if (system->first_redundant_constraint(0.0, q0) >= 0) continue;  // a loop joint that repeats a tree joint's rows
    ++tried;
    if (system->joints().size() > static_cast<std::size_t>(system->body_count())) ++closed;  // a loop joint was kept
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Eigen::Index n = q0.size(), m = system->constraint_count();
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const Eigen::VectorXd v = Eigen::VectorXd::NullaryExpr(n, [&] { return 0.3 * unit(random); });
    const Eigen::VectorXd qdd = Eigen::VectorXd::NullaryExpr(n, [&] { return unit(random); });
    // Multipliers on the bodies' reference rows only: the joints' curvature (which the constant core leaves out, and
    // the dense matrix holds) then vanishes, and the three matrices are the same matrix.
    Eigen::VectorXd mu = Eigen::VectorXd::Zero(m);
    mu.head(system->joint_row(0)) = Eigen::VectorXd::NullaryExpr(system->joint_row(0), [&] { return 1e-4 * unit(random); });
    const Eigen::VectorXd residual = Eigen::VectorXd::NullaryExpr(n, [&] { return 1e-3 * unit(random); });
    const Eigen::VectorXd phi = Eigen::VectorXd::NullaryExpr(m, [&] { return 1e-4 * unit(random); });
    const double h = 1e-3, beta_prime = 1.0 / (0.3 * h * h), gamma_prime = 0.6 / (0.3 * h);
    Eigen::SparseMatrix<double> jacobian;
    system->sparse_constraint_jacobian(0.1, q0, jacobian);
    fr::detail::DenseNewton dense(*system, beta_prime, gamma_prime);
    fr::detail::CoreInverses cores;  // one core for both: the reduced solve is what differs
    fr::detail::ConstantCoreNewton core_dense(*system, beta_prime, gamma_prime, false, cores);
    fr::detail::ConstantCoreNewton core_sparse(*system, beta_prime, gamma_prime, true, cores);
    Eigen::VectorXd x_dense, x_core, x_sparse;
    for (fr::detail::NewtonSolver* solver : {static_cast<fr::detail::NewtonSolver*>(&dense),
                                             static_cast<fr::detail::NewtonSolver*>(&core_dense),
                                             static_cast<fr::detail::NewtonSolver*>(&core_sparse)})
      solver->factor(0.1, q0, v, qdd, mu, jacobian);
    dense.solve(q0, residual, phi, x_dense);
    core_dense.solve(q0, residual, phi, x_core);
    core_sparse.solve(q0, residual, phi, x_sparse);
    ASSERT_TRUE(x_sparse.allFinite());
    // Measured: the three solutions agree to 2e-14 of their norm on these mechanisms (their saddle-point matrices'
    // SVD condition numbers are ~1e13, dominated by the rows' units, so κ ε says little); a wrong or missing block
    // changes the solution at O(1). 1e-10 leaves room for other compilers' rounding.
    EXPECT_LT((x_core - x_dense).norm(), 1e-10 * x_dense.norm());
    EXPECT_LT((x_sparse - x_dense).norm(), 1e-10 * x_dense.norm());
    EXPECT_LT((x_sparse - x_core).norm(), 1e-10 * x_dense.norm());
    EXPECT_EQ(core_sparse.reduced().matrix().rows(), core_dense.reduced().matrix().rows());
  }
  EXPECT_EQ(tried, 12);
  EXPECT_GE(closed, 4);  // closed loops among them
}

TEST(SparseNewton, AnalysesItsPatternOnceAndRefactorizes) {
  const auto system = random_mechanism(7, 8, 2);
  const Eigen::VectorXd q0 = system->initial_coordinates();
  const Eigen::Index n = q0.size(), m = system->constraint_count();
  const double h = 1e-3, beta_prime = 1.0 / (0.3 * h * h), gamma_prime = 0.6 / (0.3 * h);
  fr::detail::CoreInverses cores;
  fr::detail::ConstantCoreNewton core(*system, beta_prime, gamma_prime, true, cores);
  Eigen::SparseMatrix<double> jacobian;
  const auto& klu = dynamic_cast<const fr::detail::SparseReducedSolver&>(core.reduced());
  // Eight nearby states, as the Newton matrices of successive steps. The pattern is the union of the nonzeros: the
  // first state's has the zeros of its exact orientations; the second moves every coordinate, and after it the
  // pattern holds.
  int analysed = 0;
  for (int k = 0; k < 8; ++k) {
    const Eigen::VectorXd q = q0 + 1e-4 * k * Eigen::VectorXd::Ones(n);
    system->sparse_constraint_jacobian(0.01 * k, q, jacobian);
    core.factor(0.01 * k, q, Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(m), jacobian);
    if (k == 1) analysed = klu.analyses();
  }
  EXPECT_LE(analysed, 2);
  EXPECT_EQ(klu.analyses(), analysed);
  EXPECT_EQ(klu.pivoting_factorizations(), analysed);  // the rest kept the pivots of the pattern's first one
  // The pattern leaves out the blocks' zeros: fewer entries than the matrix's structural (dense-block) ones.
  EXPECT_LT(klu.pattern_nonzeros(), core.reduced().matrix().nonZeros());
}

namespace {

// The chain's coordinates after `steps` steps of 1 ms with the options' reduced matrix.
Eigen::VectorXd swing(const fr::System& system, fr::GeneralizedAlphaOptions options, int steps) {
  options.step = 1e-3;
  fr::GeneralizedAlpha integrator(system, options);
  for (int s = 0; s < steps; ++s) integrator.step();
  return integrator.coordinates();
}

// The chain swung for 0.1 s with the reduced matrix dense and sparse (and with the stabilised form's coupled step
// from the start, if `coupled`: StabilizedCoupling's m solves against ConstantCoreNewton::factor_coupled); the
// largest difference of a body's position at the end [m].
double dense_against_sparse(bool coupled) {
  const auto system = chain();
  std::vector<Eigen::VectorXd> end;
  for (const fr::ReducedMatrix kind : {fr::ReducedMatrix::dense, fr::ReducedMatrix::sparse}) {
    fr::GeneralizedAlphaOptions options;
    options.step = 1e-3;
    options.reduced_matrix = kind;
    options.coupled_from_start = coupled;
    options.tolerance = 1e-10;  // both converge far below the step's error, so that they can be compared
    fr::GeneralizedAlpha integrator(*system, options);
    EXPECT_EQ(integrator.sparse(), kind == fr::ReducedMatrix::sparse);
    for (int s = 0; s < 100; ++s) integrator.step();
    end.push_back(integrator.coordinates());
  }
  double worst = 0.0;
  for (int k = 0; k < 16; ++k) worst = std::max(worst, (end[1] - end[0]).segment<3>(system->offset(k)).norm());
  return worst;
}

}  // namespace

// The chain is 8.8 m long and falls about 5 cm in 0.1 s; the runs differ by the round-off of their solves and the
// Newton iteration's remainder, 1e-10 of each step's predictor-corrector distance (~1e-6 m at 0.1 s).
TEST(SparseNewton, AChainSwingsAsWithTheDenseSolve) { EXPECT_LT(dense_against_sparse(false), 1e-9); }

TEST(SparseNewton, TheSparseCoupledStepMovesAChainAsTheDenseOne) { EXPECT_LT(dense_against_sparse(true), 1e-9); }

// A long chain of rigid links, the stabilised form's alternating step: its position rows are met through
// (Φ_q W Φ_qᵀ)⁻¹, whose weakest mode (the chain bending out of its plane) amplifies any mismatch between that factor
// and the correction's direction. The links are the sample bracket's rigid body (0.347 kg, its second moment with
// the product of inertia of its L shape), 30 mm between bores that lie 10.7 mm out of the plane of the centres of
// mass, so that the swing loads the out-of-plane rows. With the factor from the Newton matrix's iterate and the
// direction Φ_q(q_n) of the step's start, 64 of them fell back to the coupled step at t = 0.025 s (scale_bench's
// chain of bracket files at 0.019 s, contracting by 0.86 per iteration); with one Jacobian for both they need none.
TEST(SparseNewton, ALongRigidChainConvergesWithTheAlternatingStep) {
  constexpr int count = 64;
  constexpr double pitch = 0.03, half = 0.015, below = -0.01065;
  Eigen::Matrix3d second_moment;
  second_moment << 1.474e-4, 0.0, 9.329e-5, 0.0, 3.786e-4, 0.0, 9.329e-5, 0.0, 3.279e-4;
  const fr::BodyModel link = fr::rigid_body_model(0.3473, second_moment, "bracket");
  const auto system = std::make_unique<fr::System>();
  for (int k = 0; k < count; ++k) {
    fr::BodyState state;
    state.position = Eigen::Vector3d(pitch * k, 0.0, 0.0);
    system->add_body(numbered("b", k), link, state);
  }
  const Eigen::VectorXd q0 = system->initial_coordinates();
  for (int k = 0; k < count; ++k) {
    const fr::Marker near = fr::point_marker(system->model(k), k, system->body_name(k), Eigen::Vector3d(-half, 0, below));
    const fr::Marker far = k == 0 ? fr::ground_marker(Eigen::Vector3d(-half, 0, below))
                                   : fr::point_marker(system->model(k - 1), k - 1, system->body_name(k - 1),
                                                      Eigen::Vector3d(half, 0, below));
    system->add_joint(fr::make_joint(numbered("j", k), fr::JointType::revolute, near, far, Eigen::Vector3d::UnitZ(),
                                     system->body_coordinates(q0, k),
                                     k == 0 ? Eigen::VectorXd() : system->body_coordinates(q0, k - 1)));
  }
  system->set_gravity(Eigen::Vector3d(0, -9.81, 0));
  fr::GeneralizedAlphaOptions options;
  options.step = 1e-3;
  fr::GeneralizedAlpha integrator(*system, options);
  for (int s = 0; s < 100; ++s) integrator.step();
  EXPECT_TRUE(integrator.warnings().empty()) << integrator.warnings().front();
  EXPECT_LT(static_cast<double>(integrator.total_iterations()) / 100.0, 6.0);
  // The rows met to the Newton iteration's remainder, 1e-6 of a step's move (~1e-5 m at 0.1 s).
  EXPECT_LT(system->constraints(integrator.time(), integrator.coordinates()).cwiseAbs().maxCoeff(), 1e-10);
}

// The Newton iteration's Φ, Φ_q v and Φ_qᵀ μ are formed joint by joint without the Jacobian (model/joint_rows.hpp), in
// parallel from 64 joints; against the sparse Jacobian's products on a random mechanism of 80 bodies (every joint type,
// GCMS, FFRF and rigid bodies, loops) away from its initial state, on one and two threads (the same bits).
TEST(SparseNewton, TheMatrixFreeProductsMatchTheJacobiansAtSystemLevel) {
  const auto system = random_mechanism(31, 80, 6);
  std::mt19937 random(5);
  std::normal_distribution<double> normal;
  const Eigen::Index n = system->coordinate_count(), m = system->constraint_count();
  Eigen::VectorXd q = system->initial_coordinates(), v(n), mu(m);
  for (Eigen::Index i = 0; i < n; ++i) {
    q(i) += 1e-3 * normal(random);
    v(i) = normal(random);
  }
  for (Eigen::Index i = 0; i < m; ++i) mu(i) = normal(random);
  const double t = 0.7;
  Eigen::SparseMatrix<double> jacobian;
  system->sparse_constraint_jacobian(t, q, jacobian);
  const Eigen::VectorXd expected_rate = jacobian * v, expected_product = jacobian.transpose() * mu;
  // The sizes of the terms summed: |J| |v| and |J|ᵀ |μ|.
  const Eigen::SparseMatrix<double> magnitude = jacobian.cwiseAbs();
  const Eigen::VectorXd rate_size = magnitude * v.cwiseAbs(), product_size = magnitude.transpose() * mu.cwiseAbs();
  Eigen::VectorXd results[2][3];
  for (const int threads : {1, 2}) {
    fr::set_threads(threads);
    Eigen::VectorXd phi, rate, product = Eigen::VectorXd::Zero(n);
    system->constraints_and_rates(t, q, v, phi, rate);
    system->add_constraint_jacobian_transpose_product(t, q, mu, product);
    const Eigen::VectorXd alone = system->constraints(t, q);
    EXPECT_TRUE(alone == phi);
    for (Eigen::Index i = 0; i < m; ++i) EXPECT_LE(std::abs(rate(i) - expected_rate(i)), 1e-13 * (1.0 + rate_size(i))) << i;
    for (Eigen::Index i = 0; i < n; ++i)
      EXPECT_LE(std::abs(product(i) - expected_product(i)), 1e-13 * (1.0 + product_size(i))) << i;
    results[threads - 1][0] = phi;
    results[threads - 1][1] = rate;
    results[threads - 1][2] = product;
  }
  fr::set_threads(1);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(results[0][k] == results[1][k]);
  ASSERT_GE(static_cast<int>(system->joints().size()), 64);  // the parallel path
}

// Per-body work runs on the threads set_threads asks for, from 64 bodies on (runtime/src/kernels/parallel.hpp);
// each body's arithmetic is the same on any thread and shared rows are summed in a fixed order, so one and two threads give the
// same bits.
TEST(SparseNewton, OneAndTwoThreadsGiveTheSameBits) {
  const auto system = chain(64);
  for (const bool coupled : {false, true}) {
    fr::GeneralizedAlphaOptions options;
    options.coupled_from_start = coupled;
    fr::set_threads(1);
    const Eigen::VectorXd one = swing(*system, options, 20);
    fr::set_threads(2);
    const Eigen::VectorXd two = swing(*system, options, 20);
    EXPECT_TRUE(one == two) << "largest difference " << (one - two).cwiseAbs().maxCoeff();
  }
  fr::set_threads(1);
}
