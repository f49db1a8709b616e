#include "flexbody/format/tet10_element.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>

namespace flexbody::format {
namespace {

// ∂N_a/∂ξ_k (row a, column k) at ξ: ∂/∂ξ_k = ∂/∂L_k − ∂/∂L_0.
Eigen::Matrix<double, 10, 3> reference_derivatives(const Eigen::Vector3d& xi) {
  const double l[4] = {1.0 - xi.sum(), xi(0), xi(1), xi(2)};
  Eigen::Matrix<double, 10, 4> by_l = Eigen::Matrix<double, 10, 4>::Zero();  // ∂N_a/∂L_i
  for (int i = 0; i < 4; ++i) by_l(i, i) = 4.0 * l[i] - 1.0;
  for (int e = 0; e < 6; ++e) {
    const auto [i, j] = kTet10Edges[static_cast<std::size_t>(e)];
    by_l(4 + e, i) = 4.0 * l[j];
    by_l(4 + e, j) = 4.0 * l[i];
  }
  Eigen::Matrix<double, 10, 3> d;
  for (int k = 0; k < 3; ++k) d.col(k) = by_l.col(k + 1) - by_l.col(0);
  return d;
}

Eigen::Matrix<double, 10, 1> shape_functions(const Eigen::Vector3d& xi) {
  const double l[4] = {1.0 - xi.sum(), xi(0), xi(1), xi(2)};
  Eigen::Matrix<double, 10, 1> n;
  for (int i = 0; i < 4; ++i) n(i) = l[i] * (2.0 * l[i] - 1.0);
  for (int e = 0; e < 6; ++e) {
    const auto [i, j] = kTet10Edges[static_cast<std::size_t>(e)];
    n(4 + e) = 4.0 * l[i] * l[j];
  }
  return n;
}

// The 4-point rule's barycentric coordinates (tet10_gauss_points): L = (a, b, b, b) and its permutations.
const double kGaussA = (5.0 + 3.0 * std::sqrt(5.0)) / 20.0, kGaussB = (5.0 - std::sqrt(5.0)) / 20.0;
constexpr double kGaussWeight = kTet10GaussWeight;

// 5-point Gauss-Legendre on [0, 1] (points and weights in closed form, to the last bit).
struct Legendre5 {
  std::array<double, 5> points{}, weights{};
};
const Legendre5& legendre5() {
  static const Legendre5 rule = [] {
    const double inner = std::sqrt(5.0 - 2.0 * std::sqrt(10.0 / 7.0)) / 3.0;  // on [−1, 1]
    const double outer = std::sqrt(5.0 + 2.0 * std::sqrt(10.0 / 7.0)) / 3.0;
    const double w_inner = (322.0 + 13.0 * std::sqrt(70.0)) / 900.0, w_outer = (322.0 - 13.0 * std::sqrt(70.0)) / 900.0;
    const double t[5] = {-outer, -inner, 0.0, inner, outer}, w[5] = {w_outer, w_inner, 128.0 / 225.0, w_inner, w_outer};
    Legendre5 r;
    for (int k = 0; k < 5; ++k) {
      r.points[static_cast<std::size_t>(k)] = 0.5 * (1.0 + t[k]);
      r.weights[static_cast<std::size_t>(k)] = 0.5 * w[k];
    }
    return r;
  }();
  return rule;
}

}  // namespace

std::array<Eigen::Vector3d, 4> tet10_gauss_points() {
  std::array<Eigen::Vector3d, 4> points;
  for (int p = 0; p < 4; ++p) {
    double l[4] = {kGaussB, kGaussB, kGaussB, kGaussB};
    l[p] = kGaussA;
    points[static_cast<std::size_t>(p)] = Eigen::Vector3d(l[1], l[2], l[3]);
  }
  return points;
}

Tet10Gradients tet10_gradients(const Tet10Nodes& nodes, const Eigen::Vector3d& xi) {
  const Eigen::Matrix<double, 10, 3> d = reference_derivatives(xi);
  const Eigen::Matrix3d jacobian = nodes.transpose() * d;  // J(r, k) = ∂x_r/∂ξ_k
  Tet10Gradients g;
  g.determinant = jacobian.determinant();
  if (g.determinant == 0.0) return g;
  g.gradients = d * jacobian.inverse();  // ∂N/∂x = ∂N/∂ξ J⁻¹
  return g;
}

Eigen::Matrix<double, 30, 30> tet10_stiffness(const Tet10Nodes& nodes, double lambda, double mu) {
  Eigen::Matrix<double, 30, 30> k = Eigen::Matrix<double, 30, 30>::Zero();
  for (const Eigen::Vector3d& xi : tet10_gauss_points()) {
    const Tet10Gradients g = tet10_gradients(nodes, xi);
    const double weight = kGaussWeight * g.determinant;
    for (int b = 0; b < 10; ++b)
      for (int a = 0; a < 10; ++a) {
        const Eigen::RowVector3d gb = g.gradients.row(b), ga = g.gradients.row(a);
        Eigen::Matrix3d block = lambda * gb.transpose() * ga + mu * ga.transpose() * gb;
        block.diagonal().array() += mu * gb.dot(ga);
        k.block<3, 3>(3 * b, 3 * a) += weight * block;
      }
  }
  return k;
}

Eigen::Matrix<double, 10, 10> tet10_mass(const Tet10Nodes& nodes, double density, Tet10MassRule rule) {
  if (rule == Tet10MassRule::four_point) {
    Eigen::Matrix<double, 10, 10> m = Eigen::Matrix<double, 10, 10>::Zero();
    for (const Eigen::Vector3d& xi : tet10_gauss_points()) {
      const double det = (nodes.transpose() * reference_derivatives(xi)).determinant();
      const Eigen::Matrix<double, 10, 1> n = shape_functions(xi);
      m.noalias() += (density * kGaussWeight * det) * n * n.transpose();
    }
    return m;
  }
  // Collapsed (Duffy) product rule: ξ_1 = u, ξ_2 = v (1 − u), ξ_3 = w (1 − u)(1 − v), dξ = (1 − u)² (1 − v) du dv dw.
  const Legendre5& g = legendre5();
  Eigen::Matrix<double, 10, 10> m = Eigen::Matrix<double, 10, 10>::Zero();
  for (std::size_t i = 0; i < 5; ++i)
    for (std::size_t j = 0; j < 5; ++j)
      for (std::size_t k = 0; k < 5; ++k) {
        const double u = g.points[i], v = g.points[j], w = g.points[k];
        const Eigen::Vector3d xi(u, v * (1.0 - u), w * (1.0 - u) * (1.0 - v));
        const double weight = g.weights[i] * g.weights[j] * g.weights[k] * (1.0 - u) * (1.0 - u) * (1.0 - v);
        const Eigen::Matrix3d jacobian = nodes.transpose() * reference_derivatives(xi);
        const Eigen::Matrix<double, 10, 1> n = shape_functions(xi);
        m.noalias() += (density * weight * jacobian.determinant()) * n * n.transpose();
      }
  return m;
}

Tet10RecoveryGradients tet10_recovery_gradients(const Tet10Nodes& nodes) {
  // Gauss point p has L_p = a, the other L_i = b: the values there of f = Σ_i c_i L_i are P c with P = b 11ᵀ + (a − b) I,
  // so the corner values are c = P⁻¹ f, P⁻¹ = (I − b 11ᵀ) / (a − b) (a + 3 b = 1).
  Tet10RecoveryGradients out;
  std::array<Eigen::Matrix<double, 10, 3>, 4> at_gauss;
  const std::array<Eigen::Vector3d, 4> points = tet10_gauss_points();
  for (std::size_t p = 0; p < 4; ++p) {
    const Tet10Gradients g = tet10_gradients(nodes, points[p]);
    if (!(g.determinant > 0.0)) {
      out.volume = std::min(0.0, g.determinant);
      for (auto& at_node : out.at_node) at_node.setZero();
      return out;
    }
    at_gauss[p] = g.gradients;
    out.volume += kGaussWeight * g.determinant;
  }
  const double diagonal = (1.0 - kGaussB) / (kGaussA - kGaussB), off = -kGaussB / (kGaussA - kGaussB);
  for (std::size_t a = 0; a < 4; ++a) {
    out.at_node[a].setZero();
    for (std::size_t p = 0; p < 4; ++p) out.at_node[a] += (p == a ? diagonal : off) * at_gauss[p];
  }
  for (std::size_t e = 0; e < 6; ++e) {
    const auto [i, j] = kTet10Edges[e];
    out.at_node[4 + e] = 0.5 * (out.at_node[static_cast<std::size_t>(i)] + out.at_node[static_cast<std::size_t>(j)]);
  }
  return out;
}

Eigen::Matrix<double, 14, 1> tet10_jacobian_determinants(const Tet10Nodes& nodes) {
  Eigen::Matrix<double, 14, 1> out;
  const std::array<Eigen::Vector3d, 4> points = tet10_gauss_points();
  for (int p = 0; p < 4; ++p) out(p) = (nodes.transpose() * reference_derivatives(points[static_cast<std::size_t>(p)])).determinant();
  const Eigen::Vector3d corners[4] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                      Eigen::Vector3d::UnitZ()};
  for (int a = 0; a < 4; ++a) out(4 + a) = (nodes.transpose() * reference_derivatives(corners[a])).determinant();
  for (int e = 0; e < 6; ++e) {
    const auto [i, j] = kTet10Edges[static_cast<std::size_t>(e)];
    out(8 + e) = (nodes.transpose() * reference_derivatives(0.5 * (corners[i] + corners[j]))).determinant();
  }
  return out;
}

}  // namespace flexbody::format
