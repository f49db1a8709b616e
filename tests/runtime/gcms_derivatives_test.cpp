// The analytic elastic forces, tangent stiffness and constraint derivatives of the improved GCMS against
// central differences (issue: 1e-6 relative). U is a polynomial of degree 4 in (a, ξ); with a step of 1e-5 of
// the coordinates' size the truncation error is ~1e-10 and the rounding error ~1e-11 relative, so 1e-6 has a
// wide margin and a wrong term (a missing factor, a transposed block) fails it by orders of magnitude.
#include "flexbody/runtime/gcms_elastic.hpp"
#include "flexbody/runtime/reference_constraints.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <functional>

namespace fr = flexbody::runtime;

namespace {

constexpr Eigen::Index kFields = 5;
constexpr double kStep = 1e-5;

// A general state: A a rotation perturbed by 1e-2 (the derivatives must hold off the constraint manifold too,
// where Newton iterates live), ξ of the size of real deformations, K̂ symmetric positive definite with
// eigenvalues between (2π 50 Hz)² and (2π 2 kHz)².
struct State {
  Eigen::MatrixXd k_hat;
  Eigen::Matrix3d a;
  Eigen::VectorXd xi;
  fr::TisserandMatrix g;
  State() {
    std::srand(7);
    const Eigen::MatrixXd q = Eigen::MatrixXd::Random(3 * kFields, 3 * kFields).householderQr().householderQ();
    const Eigen::VectorXd lambda = (Eigen::VectorXd::Random(3 * kFields).array() + 1.5) * 4e7;
    k_hat = q * lambda.asDiagonal() * q.transpose();
    a = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() +
        1e-2 * Eigen::Matrix3d::Random();
    xi = 1e-3 * Eigen::VectorXd::Random(3 * kFields);
    g = 0.05 * Eigen::MatrixXd::Random(3, kFields);
  }
  Eigen::VectorXd coordinates() const {
    Eigen::VectorXd x(9 + 3 * kFields);
    x << Eigen::Map<const Eigen::Matrix<double, 9, 1>>(a.data()), xi;
    return x;
  }
  static Eigen::Matrix3d a_of(const Eigen::VectorXd& x) { return Eigen::Map<const Eigen::Matrix3d>(x.data()); }
  static Eigen::VectorXd xi_of(const Eigen::VectorXd& x) { return x.tail(x.size() - 9); }
};

// Central differences of a vector function of [a; ξ], one column per coordinate, each step scaled to the
// coordinate block's size.
Eigen::MatrixXd central_differences(const Eigen::VectorXd& x, const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd jac(f0.size(), x.size());
  const double scale_a = 1.0, scale_xi = x.tail(x.size() - 9).cwiseAbs().maxCoeff();
  for (Eigen::Index c = 0; c < x.size(); ++c) {
    const double h = kStep * (c < 9 ? scale_a : scale_xi);
    Eigen::VectorXd plus = x, minus = x;
    plus(c) += h;
    minus(c) -= h;
    jac.col(c) = (f(plus) - f(minus)) / (2 * h);
  }
  return jac;
}

double relative_error(const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& reference) {
  return (analytic - reference).norm() / reference.norm();
}

}  // namespace

TEST(GcmsElastic, GradientMatchesCentralDifferencesOfTheEnergy) {
  const State s;
  const fr::ElasticForces forces = fr::elastic_forces(s.k_hat, s.a, s.xi);
  // U = ½ ξ̄ᵀ K̂ ξ̄ by hand.
  const Eigen::VectorXd xi_bar = fr::body_frame_coordinates(s.a, s.xi);
  EXPECT_NEAR(forces.energy, 0.5 * xi_bar.dot(s.k_hat * xi_bar), 1e-14 * forces.energy);
  const Eigen::MatrixXd numeric = central_differences(s.coordinates(), [&](const Eigen::VectorXd& x) {
    return Eigen::VectorXd::Constant(1, fr::elastic_forces(s.k_hat, State::a_of(x), State::xi_of(x)).energy);
  });
  Eigen::VectorXd analytic(9 + 3 * kFields);
  analytic << forces.grad_a, forces.grad_xi;
  EXPECT_LT(relative_error(analytic.transpose(), numeric), 1e-6);
}

TEST(GcmsElastic, TangentMatchesCentralDifferencesOfTheGradient) {
  const State s;
  const fr::ElasticTangent t = fr::elastic_tangent(s.k_hat, s.a, s.xi);
  const Eigen::Index n = 9 + 3 * kFields;
  Eigen::MatrixXd analytic(n, n);
  analytic << t.aa, t.a_xi, t.a_xi.transpose(), t.xi_xi;
  const Eigen::MatrixXd numeric = central_differences(s.coordinates(), [&](const Eigen::VectorXd& x) {
    const fr::ElasticForces f = fr::elastic_forces(s.k_hat, State::a_of(x), State::xi_of(x));
    Eigen::VectorXd grad(n);
    grad << f.grad_a, f.grad_xi;
    return grad;
  });
  EXPECT_LT(relative_error(analytic, numeric), 1e-6);
  // Each block on its own, so that a small block cannot hide behind a large one.
  EXPECT_LT(relative_error(t.aa, numeric.topLeftCorner(9, 9)), 1e-6);
  EXPECT_LT(relative_error(t.a_xi, numeric.topRightCorner(9, n - 9)), 1e-6);
  EXPECT_LT(relative_error(t.xi_xi, numeric.bottomRightCorner(n - 9, n - 9)), 1e-6);
}

TEST(GcmsElastic, EnergyIsInvariantUnderARigidRotation) {
  // Rotating the body and its fields together (A -> R A, ξ_f -> R ξ_f) leaves ξ̄ and U unchanged: the
  // corotational property that separates GCMS from a linear model. Exact up to rounding.
  const State s;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, -1, 0.2).normalized()).toRotationMatrix();
  Eigen::VectorXd rotated = s.xi;
  for (Eigen::Index f = 0; f < kFields; ++f) rotated.segment<3>(3 * f) = r * s.xi.segment<3>(3 * f);
  const double u0 = fr::elastic_forces(s.k_hat, s.a, s.xi).energy;
  EXPECT_NEAR(fr::elastic_forces(s.k_hat, r * s.a, rotated).energy, u0, 1e-13 * u0);
}

TEST(ReferenceConstraints, ResidualOfAnOrthogonalUndeformedState) {
  const State s;
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_LT(fr::reference_residual(s.g, rotation, Eigen::VectorXd::Zero(3 * kFields)).norm(), 1e-15);
  // Tisserand rows by hand: Σ_f g_f × Aᵀ ξ_f.
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (Eigen::Index f = 0; f < kFields; ++f) t += s.g.col(f).cross(s.a.transpose() * s.xi.segment<3>(3 * f));
  EXPECT_LT((fr::reference_residual(s.g, s.a, s.xi).tail<3>() - t).norm(), 1e-15);
}

TEST(ReferenceConstraints, JacobianAndHessianMatchCentralDifferences) {
  const State s;
  const Eigen::VectorXd x = s.coordinates();
  const Eigen::MatrixXd numeric_jacobian = central_differences(x, [&](const Eigen::VectorXd& y) {
    return Eigen::VectorXd(fr::reference_residual(s.g, State::a_of(y), State::xi_of(y)));
  });
  const Eigen::MatrixXd jacobian = fr::reference_jacobian(s.g, s.a, s.xi);
  EXPECT_LT(relative_error(jacobian.topRows(6), numeric_jacobian.topRows(6)), 1e-6);
  EXPECT_LT(relative_error(jacobian.bottomRows(3), numeric_jacobian.bottomRows(3)), 1e-6);
  const Eigen::Matrix<double, 9, 1> lambda = Eigen::Matrix<double, 9, 1>::Random();
  const Eigen::MatrixXd numeric_hessian = central_differences(x, [&](const Eigen::VectorXd& y) {
    return Eigen::VectorXd(fr::reference_jacobian(s.g, State::a_of(y), State::xi_of(y)).transpose() * lambda);
  });
  EXPECT_LT(relative_error(fr::reference_hessian(s.g, s.a, s.xi, lambda), numeric_hessian), 1e-6);
}

TEST(GcmsElastic, SparseStiffnessGivesTheDenseResults) {
  // The full-order body stores K̂ = K̄ sparse: the same forces and tangent as the dense code, to round-off.
  const State s;
  const Eigen::SparseMatrix<double> sparse = s.k_hat.sparseView();
  const fr::ElasticForces dense_f = fr::elastic_forces(s.k_hat, s.a, s.xi), sparse_f = fr::elastic_forces(sparse, s.a, s.xi);
  EXPECT_NEAR(sparse_f.energy, dense_f.energy, 1e-13 * dense_f.energy);
  EXPECT_LT((sparse_f.grad_a - dense_f.grad_a).norm(), 1e-13 * dense_f.grad_a.norm());
  EXPECT_LT((sparse_f.grad_xi - dense_f.grad_xi).norm(), 1e-13 * dense_f.grad_xi.norm());
  const fr::ElasticTangent dense_t = fr::elastic_tangent(s.k_hat, s.a, s.xi), sparse_t = fr::elastic_tangent(sparse, s.a, s.xi);
  EXPECT_LT((sparse_t.aa - dense_t.aa).norm(), 1e-13 * dense_t.aa.norm());
  EXPECT_LT((sparse_t.a_xi - dense_t.a_xi).norm(), 1e-13 * dense_t.a_xi.norm());
  EXPECT_LT((sparse_t.xi_xi - dense_t.xi_xi).norm(), 1e-13 * dense_t.xi_xi.norm());
}

TEST(ReferenceConstraints, HessianRowsOfAAreTheFullHessiansNonZeroPart) {
  // reference_hessian_a_rows is all of the Hessian that is not zero: its ξξ block vanishes.
  const State s;
  Eigen::Matrix<double, 9, 1> lambda;
  lambda << 0.3, -1.2, 0.7, 2.0, -0.4, 0.9, 1.5, -2.5, 0.8;
  const Eigen::MatrixXd full = fr::reference_hessian(s.g, s.a, s.xi, lambda);
  const Eigen::Matrix<double, 9, Eigen::Dynamic> rows = fr::reference_hessian_a_rows(s.g, s.xi, lambda);
  EXPECT_EQ((full.topRows<9>() - rows).norm(), 0.0);
  EXPECT_EQ(full.bottomRightCorner(3 * kFields, 3 * kFields).norm(), 0.0);
  EXPECT_LT((full - full.transpose()).norm(), 1e-15 * full.norm());
}

TEST(ReferenceConstraints, TransposedProductEqualsTheJacobiansTranspose) {
  // The Newton residual takes Φ_qᵀ μ without forming Φ_q: the same numbers as the Jacobian (itself checked
  // against central differences above).
  const State s;
  Eigen::Matrix<double, 9, 1> mu;
  mu << 0.3, -1.2, 0.7, 2.0, -0.4, 0.9, 1.5, -2.5, 0.8;
  const Eigen::VectorXd expected = fr::reference_jacobian(s.g, s.a, s.xi).transpose() * mu;
  EXPECT_LT((fr::reference_jacobian_transpose_product(s.g, s.a, s.xi, mu) - expected).norm(), 1e-14 * expected.norm());
}

TEST(ReferenceConstraints, ProductEqualsTheJacobianTimesTheVelocity) {
  // The velocity constraints of the stabilised index-2 form take Φ_q v without forming Φ_q.
  const State s;
  Eigen::VectorXd v(9 + s.xi.size());
  for (Eigen::Index i = 0; i < v.size(); ++i) v(i) = std::sin(1.7 * static_cast<double>(i) + 0.3);
  const Eigen::Matrix3d a_dot = Eigen::Map<const Eigen::Matrix3d>(v.data());
  const Eigen::VectorXd xi_dot = v.tail(s.xi.size());
  const Eigen::VectorXd expected = fr::reference_jacobian(s.g, s.a, s.xi) * v;
  EXPECT_LT((fr::reference_jacobian_product(s.g, s.a, s.xi, a_dot, xi_dot) - expected).norm(), 1e-14 * expected.norm());
}
