// The FFRF body (ffrf_model.hpp, ffrf_dynamics.hpp) against what it stands for, on a small synthetic "mesh" whose
// nodal sums are cheap: 25 nodes with a random symmetric positive definite scalar mass M_s, random fields Ῡ' and
// random mode coefficients, so that no term can hide behind an orthogonality the body files happen to have
// (∫ρ ψ_m ≠ 0, a modal mass that is not I, a frame origin off the centre of mass).
//
// - Its residual is the virtual work of the nodal inertia forces, Lᵀ (M_s ⊗ I3)(r̈ − g) with r the nodal positions
//   and L = ∂r/∂q, plus K_ff η, on the constraint manifold (pᵀp = 1 and its time derivatives) and in the directions
//   the normalisation leaves free. r̈ comes from second differences of r along the path q + s v + ½ s² a.
// - Its mass, stiffness and damping tangents are the derivatives of the residual by central differences, off the
//   manifold too (where Newton iterates live).
#include "flexbody/runtime/ffrf_dynamics.hpp"
#include "flexbody/runtime/ffrf_model.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <functional>

namespace fr = flexbody::runtime;

namespace {

constexpr Eigen::Index kNodes = 25, kFields = 6, kModes = 3;

struct Synthetic {
  Eigen::MatrixXd m_s;        // n_n square
  Eigen::MatrixXd y;          // n_n x (4 + n_f): [1, X̄, Ῡ']
  fr::BodyModel model;
  Synthetic() {
    std::srand(11);
    const Eigen::MatrixXd b = Eigen::MatrixXd::Random(kNodes, kNodes);
    m_s = 0.02 * (b * b.transpose()) + 0.5 * Eigen::MatrixXd::Identity(kNodes, kNodes);  // [kg]
    y.resize(kNodes, 4 + kFields);
    y.col(0).setOnes();
    y.middleCols<3>(1) = 0.4 * Eigen::MatrixXd::Random(kNodes, 3);  // [m]
    y.rightCols(kFields) = 0.3 * Eigen::MatrixXd::Random(kNodes, kFields);
    model.source = "synthetic";
    model.modes = kModes;
    model.mass = m_s.sum();
    model.mass_matrix = y.transpose() * m_s * y;
    const Eigen::MatrixXd k = Eigen::MatrixXd::Random(3 * kFields, 3 * kFields);
    model.stiffness = 1e4 * (k * k.transpose()) + 1e3 * Eigen::MatrixXd::Identity(3 * kFields, 3 * kFields);
    model.tisserand = model.mass_matrix.block(1, 4, 3, kFields);
    model.mode_coefficients = Eigen::MatrixXd::Random(kFields, 3 * kModes);
    flexbody::format::Interface root;
    root.name = "root";
    Eigen::VectorXd w = Eigen::VectorXd::Zero(kNodes);
    w.head(4) << 0.1, 0.2, 0.3, 0.4;
    root.y_row = y.transpose() * w;
    root.rotation = Eigen::MatrixXd::Random(3, 3 * kFields);
    model.interfaces.push_back(root);
  }
  // Nodal positions r (3 n_n) of FFRF coordinates q, straight from the definition r_i = τ + A(p) (X̄_i + Σ u_m(i) η_m).
  Eigen::VectorXd positions(const fr::FfrfModel& f, const Eigen::VectorXd& q) const {
    const Eigen::Matrix3d a = fr::euler_rotation(q.segment<4>(3));
    Eigen::VectorXd r(3 * kNodes);
    for (Eigen::Index i = 0; i < kNodes; ++i) {
      Eigen::Vector3d u = y.row(i).segment<3>(1).transpose();
      for (Eigen::Index m = 0; m < kModes; ++m) u += q(7 + m) * f.shapes.middleCols<3>(3 * m).transpose() * y.row(i).transpose();
      r.segment<3>(3 * i) = q.head<3>() + a * u;
    }
    return r;
  }
};

const Synthetic& synthetic() {
  static const Synthetic s;
  return s;
}

Eigen::MatrixXd central_differences(const Eigen::VectorXd& x, double step,
                                    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd jac(f0.size(), x.size());
  for (Eigen::Index c = 0; c < x.size(); ++c) {
    Eigen::VectorXd plus = x, minus = x;
    plus(c) += step;
    minus(c) -= step;
    jac.col(c) = (f(plus) - f(minus)) / (2 * step);
  }
  return jac;
}

// A state on the manifold: p unit, pᵀṗ = 0, pᵀp̈ = −|ṗ|² (the normalisation and its two time derivatives).
struct State {
  Eigen::VectorXd q, v, a;
};
State on_manifold() {
  State s;
  s.q = Eigen::VectorXd::Random(7 + kModes);
  s.v = Eigen::VectorXd::Random(7 + kModes);
  s.a = Eigen::VectorXd::Random(7 + kModes);
  const Eigen::Vector4d p = s.q.segment<4>(3).normalized();
  Eigen::Vector4d p_d = s.v.segment<4>(3), p_dd = s.a.segment<4>(3);
  p_d = 3.0 * (p_d - p.dot(p_d) * p);                // a few rad/s
  p_dd -= (p.dot(p_dd) + p_d.squaredNorm()) * p;     // pᵀp̈ = −|ṗ|²
  s.q.segment<4>(3) = p;
  s.v.segment<4>(3) = p_d;
  s.a.segment<4>(3) = p_dd;
  s.q.tail(kModes) *= 0.05;
  return s;
}

}  // namespace

TEST(FfrfDynamics, ResidualIsTheVirtualWorkOfTheNodalInertiaForces) {
  const Synthetic& s = synthetic();
  const Eigen::Vector3d g(0.3, -9.81, 1.2);
  for (const fr::FloatingFrame frame : {fr::FloatingFrame::mean_axis, fr::FloatingFrame::interface}) {
    SCOPED_TRACE(frame == fr::FloatingFrame::mean_axis ? "mean axis" : "interface");
    const fr::FfrfModel f = fr::make_ffrf_model(s.model, frame, "root");
    const State st = on_manifold();
    auto r_of = [&](const Eigen::VectorXd& q) { return s.positions(f, q); };
    const Eigen::MatrixXd l = central_differences(st.q, 1e-6, r_of);
    // r̈ = d²/ds² r(q + s v + ½ s² a) at s = 0 (r is a polynomial of degree 6 in s: second differences at 1e-3 are
    // exact to ~1e-6 of r̈).
    const double h = 1e-3;
    auto along = [&](double t) { return r_of(st.q + t * st.v + 0.5 * t * t * st.a); };
    const Eigen::VectorXd r_dd = (along(h) - 2.0 * along(0.0) + along(-h)) / (h * h);
    Eigen::VectorXd accel = r_dd;
    for (Eigen::Index i = 0; i < kNodes; ++i) accel.segment<3>(3 * i) -= g;
    Eigen::VectorXd mass_times = Eigen::VectorXd::Zero(3 * kNodes);  // (M_s ⊗ I3) (r̈ − g)
    for (Eigen::Index i = 0; i < kNodes; ++i)
      for (Eigen::Index j = 0; j < kNodes; ++j) mass_times.segment<3>(3 * i) += s.m_s(i, j) * accel.segment<3>(3 * j);
    Eigen::VectorXd expected = l.transpose() * mass_times;
    expected.tail(kModes) += f.modal_stiffness * st.q.tail(kModes);
    const Eigen::VectorXd residual = fr::ffrf_residual(f, st.q, st.v, st.a, g);
    // The normalisation's multiplier takes up the component along ∂(pᵀp)/∂p = 2p: compare the rest.
    const Eigen::Vector4d p = st.q.segment<4>(3);
    auto tangential = [&p](Eigen::VectorXd x) {
      x.segment<4>(3) -= p.dot(x.segment<4>(3)) * p;
      return x;
    };
    const double scale = expected.cwiseAbs().maxCoeff();
    EXPECT_LT((tangential(residual) - tangential(expected)).cwiseAbs().maxCoeff(), 1e-6 * scale)
        << "residual\n" << tangential(residual).transpose() << "\nnodal\n" << tangential(expected).transpose();
    // The kinetic energy is the nodal one, ½ ṙᵀ (M_s ⊗ I3) ṙ with ṙ = L q̇.
    const Eigen::VectorXd r_d = l * st.v;
    double nodal = 0.0;
    for (Eigen::Index i = 0; i < kNodes; ++i)
      for (Eigen::Index j = 0; j < kNodes; ++j) nodal += 0.5 * s.m_s(i, j) * r_d.segment<3>(3 * i).dot(r_d.segment<3>(3 * j));
    EXPECT_NEAR(fr::ffrf_kinetic_energy(f, st.q, st.v), nodal, 1e-8 * nodal);
  }
}

TEST(FfrfDynamics, TangentsAreTheResidualsDerivatives) {
  const Synthetic& s = synthetic();
  const Eigen::Vector3d g(0.3, -9.81, 1.2);
  for (const fr::FloatingFrame frame : {fr::FloatingFrame::mean_axis, fr::FloatingFrame::interface}) {
    SCOPED_TRACE(frame == fr::FloatingFrame::mean_axis ? "mean axis" : "interface");
    fr::BodyModel damped = s.model;
    damped.damping = 1e-3 * s.model.stiffness;
    const fr::FfrfModel f = fr::make_ffrf_model(damped, frame, "root");
    // Off the manifold: Newton's iterates are not unit quaternions.
    Eigen::VectorXd q = Eigen::VectorXd::Random(7 + kModes), v = 3.0 * Eigen::VectorXd::Random(7 + kModes),
                    a = 5.0 * Eigen::VectorXd::Random(7 + kModes);
    q.tail(kModes) *= 0.05;
    const fr::FfrfTangent t = fr::ffrf_tangent(f, q, v, a, g);
    // R is a polynomial of degree ≤ 4 in each argument: central differences with a step of 1e-5 are exact to
    // ~1e-10 relative (truncation) and ~1e-11 (rounding); 1e-7 catches any wrong term by orders of magnitude.
    const double step = 1e-5;
    const Eigen::MatrixXd stiffness = central_differences(q, step, [&](const Eigen::VectorXd& x) { return fr::ffrf_residual(f, x, v, a, g); });
    const Eigen::MatrixXd damping = central_differences(v, step, [&](const Eigen::VectorXd& x) { return fr::ffrf_residual(f, q, x, a, g); });
    const Eigen::MatrixXd mass = central_differences(a, step, [&](const Eigen::VectorXd& x) { return fr::ffrf_residual(f, q, v, x, g); });
    auto relative = [](const Eigen::MatrixXd& x, const Eigen::MatrixXd& ref) {
      return (x - ref).cwiseAbs().maxCoeff() / ref.cwiseAbs().maxCoeff();
    };
    EXPECT_LT(relative(t.stiffness, stiffness), 1e-7) << "analytic\n" << t.stiffness << "\nfd\n" << stiffness;
    EXPECT_LT(relative(t.damping, damping), 1e-7) << "analytic\n" << t.damping << "\nfd\n" << damping;
    EXPECT_LT(relative(t.mass, mass), 1e-7);
    EXPECT_LT((t.mass - t.mass.transpose()).cwiseAbs().maxCoeff(), 1e-12 * t.mass.cwiseAbs().maxCoeff());
    // M x is the mass matrix's product, and the forces are −R at zero acceleration.
    const Eigen::VectorXd x = Eigen::VectorXd::Random(7 + kModes);
    EXPECT_LT((fr::ffrf_mass_product(f, q, x) - t.mass * x).cwiseAbs().maxCoeff(), 1e-12 * (t.mass * x).cwiseAbs().maxCoeff());
    const Eigen::VectorXd r = fr::ffrf_residual(f, q, v, a, g);
    EXPECT_LT((r - (t.mass * a - fr::ffrf_forces(f, q, v, g))).cwiseAbs().maxCoeff(), 1e-12 * r.cwiseAbs().maxCoeff());
  }
}

TEST(FfrfModel, InterfaceFrameHoldsTheInterfaceStill) {
  // In the interface frame every mode leaves the interface's point and rotation where they are: y_rowᵀ W_m = 0 and
  // R c_m − θ_m = 0.
  const Synthetic& s = synthetic();
  const fr::FfrfModel f = fr::make_ffrf_model(s.model, fr::FloatingFrame::interface, "root");
  const auto& root = s.model.interfaces.front();
  for (Eigen::Index m = 0; m < kModes; ++m) {
    const Eigen::Vector3d moved = f.shapes.middleCols<3>(3 * m).transpose() * root.y_row;
    Eigen::VectorXd c(3 * kFields);
    for (Eigen::Index k = 0; k < kFields; ++k) c.segment<3>(3 * k) = f.shapes.block<1, 3>(4 + k, 3 * m).transpose();
    const Eigen::Vector3d turned = root.rotation * c + f.rigid_rotations.col(m);
    EXPECT_LT(moved.norm(), 1e-13);
    EXPECT_LT(turned.norm(), 1e-13);
  }
  EXPECT_THROW(static_cast<void>(fr::make_ffrf_model(s.model, fr::FloatingFrame::interface, "tip")), std::invalid_argument);
}

TEST(FfrfDynamics, EulerParametersRoundTrip) {
  const Eigen::Matrix3d a = Eigen::AngleAxisd(2.9, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector4d p = fr::euler_parameters(a);
  EXPECT_NEAR(p.norm(), 1.0, 1e-15);
  EXPECT_LT((fr::euler_rotation(p) - a).cwiseAbs().maxCoeff(), 1e-15);
  const Eigen::Vector3d x(0.3, -0.7, 1.1);
  const Eigen::MatrixXd fd = central_differences(p, 1e-6, [&](const Eigen::VectorXd& pp) {
    return Eigen::VectorXd(fr::euler_rotation(pp.head<4>()) * x);
  });
  EXPECT_LT((fr::euler_rotation_derivative(p, x) - fd).cwiseAbs().maxCoeff(), 1e-9);
}
