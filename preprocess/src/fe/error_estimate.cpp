#include "flexbody/preprocess/error_estimate.hpp"

#include "flexbody/format/tet10_element.hpp"
#include "flexbody/format/tet4_element.hpp"
#include "flexbody/preprocess/stress_recovery.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace flexbody::preprocess {
namespace {

using Voigt = Eigen::Matrix<double, 6, 1>;  // xx, yy, zz, xy, xz, yz (tensor shear components)

// s : C⁻¹ t, the complementary energy's bilinear form of an isotropic material: ε = ((1 + ν) σ − ν tr(σ) I) / E.
double compliance_product(const Voigt& s, const Voigt& t, double young, double poisson) {
  const double contracted = s.head<3>().dot(t.head<3>()) + 2.0 * s.tail<3>().dot(t.tail<3>());
  return ((1.0 + poisson) * contracted - poisson * s.head<3>().sum() * t.head<3>().sum()) / young;
}

// σ = λ tr(ε) I + 2 μ ε of the displacement gradient h, in Voigt order.
Voigt voigt_stress(const Eigen::Matrix3d& h, double lambda, double mu) {
  const Eigen::Matrix3d strain = 0.5 * (h + h.transpose());
  const Eigen::Matrix3d sigma = lambda * strain.trace() * Eigen::Matrix3d::Identity() + 2.0 * mu * strain;
  Voigt out;
  out << sigma(0, 0), sigma(1, 1), sigma(2, 2), sigma(0, 1), sigma(0, 2), sigma(1, 2);
  return out;
}

// (1 − η²/λ_h)^(−1/2) − 1 per mode (+inf from η² ≥ λ_h on; 0 for a zero frequency).
Eigen::VectorXd relative_frequency_errors(const Eigen::VectorXd& error_energy, const Eigen::VectorXd& frequencies_hz) {
  Eigen::VectorXd estimate(error_energy.size());
  for (Eigen::Index k = 0; k < error_energy.size(); ++k) {
    const double omega = 2.0 * std::numbers::pi * frequencies_hz(k), eigenvalue = omega * omega;
    const double ratio = eigenvalue > 0.0 ? error_energy(k) / eigenvalue : 0.0;
    estimate(k) = ratio < 1.0 ? 1.0 / std::sqrt(1.0 - ratio) - 1.0 : std::numeric_limits<double>::infinity();
  }
  return estimate;
}

void check_mode_sizes(Eigen::Index nodes, const Eigen::MatrixXd& modes, const Eigen::VectorXd& frequencies_hz) {
  if (modes.rows() != 3 * nodes || frequencies_hz.size() != modes.cols())
    throw std::invalid_argument("frequency_error_estimates: the modes do not match the mesh or the frequencies");
}

// Each mode's error energy η², Σ_e of what `add(e, energy)` adds for element e into the m-vector `energy` (zeroed per
// element), and each element's share max_k η²_{e,k} / λ_k: summed over fixed blocks of elements in parallel, the
// blocks then added in order, so the same result for any thread count.
template <typename AddElement>
FrequencyErrorEstimate error_energies(Eigen::Index elements, const Eigen::VectorXd& frequencies_hz,
                                      const AddElement& add) {
  constexpr Eigen::Index kBlock = 1024;
  const Eigen::Index modes = frequencies_hz.size(), blocks = (elements + kBlock - 1) / kBlock;
  Eigen::VectorXd inverse_eigenvalue(modes);
  for (Eigen::Index k = 0; k < modes; ++k) {
    const double omega = 2.0 * std::numbers::pi * frequencies_hz(k);
    inverse_eigenvalue(k) = omega > 0.0 ? 1.0 / (omega * omega) : 0.0;  // a rigid-body mode has no share
  }
  FrequencyErrorEstimate out;
  out.element_shares.resize(elements);
  Eigen::MatrixXd partial = Eigen::MatrixXd::Zero(modes, blocks);
#pragma omp parallel for schedule(dynamic)
  for (Eigen::Index block = 0; block < blocks; ++block) {
    Eigen::VectorXd energy(modes);
    for (Eigen::Index e = block * kBlock; e < std::min(elements, (block + 1) * kBlock); ++e) {
      energy.setZero();
      add(e, energy);
      partial.col(block) += energy;
      out.element_shares(e) = modes > 0 ? energy.cwiseProduct(inverse_eigenvalue).maxCoeff() : 0.0;
    }
  }
  out.relative = relative_frequency_errors(partial.rowwise().sum(), frequencies_hz);
  return out;
}

}  // namespace

FrequencyErrorEstimate estimate_frequency_errors(const TetMesh& mesh, const Material& material,
                                                 const Eigen::MatrixXd& modes, const Eigen::VectorXd& frequencies_hz) {
  check_mode_sizes(mesh.node_count(), modes, frequencies_hz);
  const Eigen::MatrixXd recovered = nodal_stresses(mesh, material, modes);  // 6 n x m, σ* at the nodes
  const double lambda = lame_lambda(material), mu = shear_modulus(material);
  return error_energies(mesh.element_count(), frequencies_hz, [&](Eigen::Index e, Eigen::VectorXd& out) {
    Eigen::Matrix<double, 4, 3> corners;
    for (int a = 0; a < 4; ++a) corners.row(a) = mesh.nodes.row(mesh.tets(e, a));
    const format::Tet4Geometry g = format::tet4_geometry(corners);
    for (Eigen::Index k = 0; k < modes.cols(); ++k) {
      Eigen::Matrix3d h = Eigen::Matrix3d::Zero();  // ∇u = Σ_a u_a ⊗ ∇N_a
      for (int a = 0; a < 4; ++a) h += modes.col(k).segment<3>(3 * mesh.tets(e, a)) * g.gradients.row(a);
      const Voigt element = voigt_stress(h, lambda, mu);
      Voigt d[4];
      for (int a = 0; a < 4; ++a) d[a] = recovered.col(k).segment<6>(6 * mesh.tets(e, a)) - element;
      double sum = 0.0;  // Σ_ab (1 + δ_ab) d_a : C⁻¹ d_b, times V / 20
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          sum += (a == b ? 2.0 : 1.0) * compliance_product(d[a], d[b], material.youngs_modulus, material.poisson_ratio);
      out(k) += std::abs(g.volume) / 20.0 * sum;
    }
  });
}

FrequencyErrorEstimate estimate_frequency_errors(const Tet10Mesh& mesh, const Material& material,
                                                 const Eigen::MatrixXd& modes, const Eigen::VectorXd& frequencies_hz) {
  check_mode_sizes(mesh.node_count(), modes, frequencies_hz);
  const Eigen::MatrixXd recovered = nodal_stresses(mesh, material, modes);  // 6 n x m, σ* at every node
  const double lambda = lame_lambda(material), mu = shear_modulus(material);
  // The 4-point Gauss rule (degree 2; weights 1/24 of the reference volume 1/6), at barycentric (a, b, b, b) and
  // its permutations; the shape functions' values there: N_i = L_i (2 L_i − 1), N_ij = 4 L_i L_j.
  constexpr double a = 0.5854101966249685, b = 0.1381966011250105;
  const double barycentric[4][4] = {{a, b, b, b}, {b, a, b, b}, {b, b, a, b}, {b, b, b, a}};
  Eigen::Matrix<double, 4, 10> shape;
  for (int g = 0; g < 4; ++g) {
    const double* l = barycentric[g];
    for (int i = 0; i < 4; ++i) shape(g, i) = l[i] * (2.0 * l[i] - 1.0);
    for (int k = 0; k < 6; ++k) {
      const auto [i, j] = format::kTet10Edges[static_cast<std::size_t>(k)];
      shape(g, 4 + k) = 4.0 * l[i] * l[j];
    }
  }
  return error_energies(mesh.element_count(), frequencies_hz, [&](Eigen::Index e, Eigen::VectorXd& out) {
    format::Tet10Nodes x;
    for (int c = 0; c < 10; ++c) x.row(c) = mesh.nodes.row(mesh.tets(e, c));
    for (int g = 0; g < 4; ++g) {
      const Eigen::Vector3d xi(barycentric[g][1], barycentric[g][2], barycentric[g][3]);
      const format::Tet10Gradients grad = format::tet10_gradients(x, xi);
      const double weight = std::abs(grad.determinant) / 24.0;
      for (Eigen::Index k = 0; k < modes.cols(); ++k) {
        Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
        Voigt star = Voigt::Zero();
        for (int c = 0; c < 10; ++c) {
          h += modes.col(k).segment<3>(3 * mesh.tets(e, c)) * grad.gradients.row(c);
          star += shape(g, c) * recovered.col(k).segment<6>(6 * mesh.tets(e, c));
        }
        const Voigt d = star - voigt_stress(h, lambda, mu);
        out(k) += weight * compliance_product(d, d, material.youngs_modulus, material.poisson_ratio);
      }
    }
  });
}

Eigen::VectorXd frequency_error_estimates(const TetMesh& mesh, const Material& material, const Eigen::MatrixXd& modes,
                                          const Eigen::VectorXd& frequencies_hz) {
  return estimate_frequency_errors(mesh, material, modes, frequencies_hz).relative;
}

Eigen::VectorXd frequency_error_estimates(const Tet10Mesh& mesh, const Material& material, const Eigen::MatrixXd& modes,
                                          const Eigen::VectorXd& frequencies_hz) {
  return estimate_frequency_errors(mesh, material, modes, frequencies_hz).relative;
}

}  // namespace flexbody::preprocess
