// Eigen residuals and their rounding floors (eigen_residual.hpp): the floor against a dense computation, and
// that modes which are not converged are still refused while modes at their floor are not.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/eigen_residual.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};

Eigen::MatrixXd dense_vector_mass(const fp::SparseMatrix& scalar_mass_upper) {
  const Eigen::MatrixXd ms = Eigen::MatrixXd(fp::full_from_upper(scalar_mass_upper));
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(3 * ms.rows(), 3 * ms.cols());
  for (Eigen::Index i = 0; i < ms.rows(); ++i)
    for (Eigen::Index j = 0; j < ms.cols(); ++j)
      for (int c = 0; c < 3; ++c) m(3 * i + c, 3 * j + c) = ms(i, j);
  return m;
}

// The wire clamped at x = 0 (its four root nodes tied rigidly).
fp::RigidInterface wire_root(const flexbody::test::AssembledMesh& wire) {
  std::vector<int> nodes;
  for (Eigen::Index i = 0; i < wire.mesh.nodes.rows(); ++i)
    if (wire.mesh.nodes(i, 0) == 0.0) nodes.push_back(static_cast<int>(i));
  fp::RigidInterface root;
  root.nodes = Eigen::Map<const Eigen::VectorXi>(nodes.data(), static_cast<Eigen::Index>(nodes.size()));
  root.reference_point = Eigen::Vector3d(0.0, 0.00125, 0.00125);
  return root;
}

}  // namespace

TEST(EigenResidual, FloorEqualsADenseComputation) {
  // A 4 x 2 x 2-cell block (45 nodes): every product against the explicit K̄, M̄ = M_s ⊗ I3, |K̄| and |M̄|.
  const auto block = flexbody::test::assemble(flexbody::test::box_mesh(0.2, 0.05, 0.05, 4, 2, 2), kSteel);
  const Eigen::MatrixXd k = Eigen::MatrixXd(fp::full_from_upper(block.stiffness));
  const Eigen::MatrixXd m = dense_vector_mass(block.scalar_mass);
  const Eigen::Index n = k.rows();
  // A real eigenpair (its residual cancels: the case the floor is for) and a random vector with a made-up λ.
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> dense(k, m);
  std::mt19937_64 generator(12);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd random(n);
  for (Eigen::Index i = 0; i < n; ++i) random(i) = uniform(generator);
  const std::vector<std::pair<double, Eigen::VectorXd>> pairs = {
      {dense.eigenvalues()(6), dense.eigenvectors().col(6)}, {3.0e6, random}};
  for (const auto& [lambda, phi] : pairs) {
    SCOPED_TRACE(lambda);
    const Eigen::VectorXd kphi = k * phi;
    const double floor = DBL_EPSILON * ((k.cwiseAbs() * phi.cwiseAbs()).norm() +
                                        std::abs(lambda) * (m.cwiseAbs() * phi.cwiseAbs()).norm()) / kphi.norm();
    const fp::EigenResidual r = fp::eigen_residual(block.stiffness, block.scalar_mass, lambda, phi);
    // The floor is a sum of positive terms: only the summation order differs, 1e-14 is a wide margin.
    EXPECT_NEAR(r.floor, floor, 1e-14 * floor);
    // The residual itself is known only to its floor (both products round at that level).
    EXPECT_NEAR(r.relative, (kphi - lambda * (m * phi)).norm() / kphi.norm(), 4.0 * floor);

    Eigen::VectorXd y(n), z(n);
    fp::apply_symmetric_with_magnitude(block.stiffness, phi, y, z);
    EXPECT_LT((y - kphi).norm(), 1e-14 * (k.cwiseAbs() * phi.cwiseAbs()).norm());
    EXPECT_LT((z - k.cwiseAbs() * phi.cwiseAbs()).norm(), 1e-14 * z.norm());
    fp::apply_vector_mass_with_magnitude(block.scalar_mass, phi, y, z);
    EXPECT_LT((y - m * phi).norm(), 1e-14 * (m.cwiseAbs() * phi.cwiseAbs()).norm());
    EXPECT_LT((z - m.cwiseAbs() * phi.cwiseAbs()).norm(), 1e-14 * z.norm());
  }
  // Compact block, real mode: the floor is at the level of ε itself, far below the old 1e-8.
  const Eigen::VectorXd mode = dense.eigenvectors().col(6);
  EXPECT_LT(fp::eigen_residual(block.stiffness, block.scalar_mass, dense.eigenvalues()(6), mode).floor, 1e-12);
}

TEST(EigenResidual, AcceptanceBoundIsTheLargerOfTheFixedOneAndTheScaledFloor) {
  EXPECT_EQ(fp::accepted_residual(1e-15), fp::kMinResidualBound);
  EXPECT_EQ(fp::accepted_residual(1e-7), fp::kResidualFloorFactor * 1e-7);
  const Eigen::Vector3d residuals(5e-9, 1.5e-6, 3e-7), floors(1e-14, 1e-7, 1e-8);
  // Mode 2 is 0.75 of its bound 2e-6; mode 3 is 1.5 times its bound 2e-7: refused.
  EXPECT_EQ(fp::worst_refused(residuals, floors), 2);
  EXPECT_EQ(fp::worst_refused(residuals.head(2), floors.head(2)), -1);
  EXPECT_EQ(fp::worst_refused(Eigen::Vector2d(1e-9, std::nan("")), Eigen::Vector2d(1e-9, 1e-9)), 1);
  const std::string message = fp::describe_refusal(3e-7, 1e-8);
  EXPECT_NE(message.find("relative residual 3e-07, 30 times its rounding floor 1e-08; accepted up to max(1e-08, 20 x "
                         "floor) = 2e-07"), std::string::npos) << message;
}

TEST(EigenResidual, PerturbedModeIsRefused) {
  // The wire's first free-free mode is accepted at its floor (residual 0.58 of it). Mixing in 1e-6 of the third
  // mode (an eigenvector error of 1e-6, against about residual / relative gap = 1e-8 for the computed one) puts
  // its residual 97 times above its floor (measured): refused, though it is still below 1e-5.
  const auto& wire = flexbody::test::steel_wire();
  fp::FreeFreeOptions options;
  options.modes = 4;
  const auto modes = fp::free_free_modes(wire.mesh.nodes, wire.stiffness, wire.scalar_mass, kSteel, options);
  const fp::EigenResidual converged =
      fp::eigen_residual(wire.stiffness, wire.scalar_mass, modes.eigenvalues(0), modes.vectors.col(0));
  EXPECT_TRUE(converged.accepted());
  EXPECT_LT(converged.to_floor(), 1.0);
  for (const double amount : {1e-6, 1e-4}) {
    SCOPED_TRACE(amount);
    Eigen::VectorXd phi = modes.vectors.col(0) + amount * modes.vectors.col(2);
    Eigen::VectorXd kphi(phi.size()), mphi(phi.size());
    fp::apply_symmetric(wire.stiffness, phi, kphi);
    fp::apply_vector_mass(wire.scalar_mass, phi, mphi);
    const double rayleigh = phi.dot(kphi) / phi.dot(mphi);  // the best λ for this vector
    const fp::EigenResidual perturbed = fp::eigen_residual(wire.stiffness, wire.scalar_mass, rayleigh, phi);
    EXPECT_FALSE(perturbed.accepted()) << perturbed.relative << " " << perturbed.floor;
    EXPECT_GT(perturbed.to_floor(), 2.0 * fp::kResidualFloorFactor);
  }
}

TEST(EigenResidual, ModesOfAnEarlyStoppedSolverAreRefused) {
  // ARPACK stopped at tol 1e-6 with a shift far above the modes, -(2 pi 10 kHz)^2, where Lanczos converges
  // slowly: its Ritz vectors are off by far more than rounding (ratios 5e4 clamped, 2e5 free-free measured).
  // Both are refused with the residual, the floor and the bound in the message. At the default tol 1e-12
  // the same shift gives residuals within 3.2 times the floor: accepted.
  const auto& wire = flexbody::test::steel_wire();
  const double far_shift = -std::pow(2.0 * std::numbers::pi * 1e4, 2);
  auto expect_refusal = [](auto&& compute, const std::string& what) {
    try {
      (void)compute();
      ADD_FAILURE() << what << ": accepted";
    } catch (const std::runtime_error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(what), std::string::npos) << message;
      EXPECT_NE(message.find("is not converged: relative residual"), std::string::npos) << message;
      EXPECT_NE(message.find("times its rounding floor"), std::string::npos) << message;
      EXPECT_NE(message.find("accepted up to max(1e-08, 20 x floor)"), std::string::npos) << message;
    }
  };
  fp::CraigBamptonOptions cb;
  cb.fixed_interface_modes = 4;
  cb.shift = far_shift;
  cb.solver.tolerance = 1e-6;
  expect_refusal([&] {
    return fp::craig_bampton_modes(wire.mesh.nodes, wire.stiffness, wire.scalar_mass, kSteel, {wire_root(wire)}, cb);
  }, "craig-bampton: fixed-interface mode");
  fp::FreeFreeOptions ff;
  ff.modes = 4;
  ff.shift = far_shift;
  ff.solver.tolerance = 1e-6;
  expect_refusal([&] { return fp::free_free_modes(wire.mesh.nodes, wire.stiffness, wire.scalar_mass, kSteel, ff); },
                 "free-free modes: mode");

  cb.solver.tolerance = ff.solver.tolerance = 1e-12;
  const auto clamped =
      fp::craig_bampton_modes(wire.mesh.nodes, wire.stiffness, wire.scalar_mass, kSteel, {wire_root(wire)}, cb);
  EXPECT_LT((clamped.fixed_interface_residuals.array() / clamped.fixed_interface_residual_floors.array()).maxCoeff(),
            fp::kResidualFloorFactor);
  const auto free_free = fp::free_free_modes(wire.mesh.nodes, wire.stiffness, wire.scalar_mass, kSteel, ff);
  EXPECT_LT((free_free.relative_residuals.array() / free_free.residual_floors.array()).maxCoeff(),
            fp::kResidualFloorFactor);
}
