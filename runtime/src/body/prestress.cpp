#include "flexbody/runtime/prestress.hpp"

#include <stdexcept>

namespace flexbody::runtime {

Prestress make_prestress(const format::BodyData& body, Eigen::Index n_f,
                         const std::vector<format::Interface>& interfaces) {
  const format::GeometricStiffness& g = body.geometric_stiffness;
  Prestress p;
  p.interface_cases.assign(interfaces.size(), {-1, -1, -1, -1, -1, -1});
  for (std::size_t k = 0; k < g.cases.size(); ++k) {
    const std::string& name = g.cases[k];
    const std::size_t colon = name.rfind(':');
    if (colon == std::string::npos) continue;  // the reader refuses such names; nothing to weight it by
    const std::string source = name.substr(0, colon), load = name.substr(colon + 1);
    const int index = static_cast<int>(p.cases.size());
    bool known = false;
    for (std::size_t c = 0; c < 6; ++c) {
      if (source == "centrifugal" && load == format::kCentrifugalCases[c]) {
        p.centrifugal[c] = index;
        known = true;
      }
      for (std::size_t i = 0; i < interfaces.size(); ++i)
        if (source == interfaces[i].name && load == format::kInterfaceLoadCases[c]) {
          p.interface_cases[i][c] = index;
          known = true;
        }
    }
    if (!known) continue;
    p.cases.push_back(name);
    p.matrices.push_back(g.matrices[k].topLeftCorner(4 + n_f, 4 + n_f));
  }
  return p;
}

void prestress_weights(const Prestress& prestress, const Eigen::Vector3d& omega_bar,
                       const std::vector<InterfaceLoad>& loads, Eigen::VectorXd& weights) {
  if (loads.size() != prestress.interface_cases.size())
    throw std::invalid_argument("prestress weights: " + std::to_string(loads.size()) + " interface loads for " +
                                std::to_string(prestress.interface_cases.size()) + " interfaces");
  weights.setZero(static_cast<Eigen::Index>(prestress.cases.size()));
  const Eigen::Matrix3d spin = omega_bar * omega_bar.transpose();  // Σ_k λ_k W_k = ω̄ ω̄ᵀ (geometric_stiffness.hpp)
  const std::array<double, 6> products = {spin(0, 0), spin(1, 1), spin(2, 2), spin(0, 1), spin(0, 2), spin(1, 2)};
  for (std::size_t c = 0; c < 6; ++c)
    if (prestress.centrifugal[c] >= 0) weights(prestress.centrifugal[c]) = products[c];
  for (std::size_t i = 0; i < loads.size(); ++i)
    for (std::size_t c = 0; c < 6; ++c) {
      const int k = prestress.interface_cases[i][c];
      if (k >= 0) weights(k) = c < 3 ? loads[i].force(static_cast<Eigen::Index>(c)) : loads[i].moment(static_cast<Eigen::Index>(c - 3));
    }
}

void weighted_sum(const std::vector<Eigen::MatrixXd>& blocks, const Eigen::VectorXd& weights, Eigen::MatrixXd& out) {
  if (static_cast<Eigen::Index>(blocks.size()) != weights.size())
    throw std::invalid_argument("prestress: " + std::to_string(weights.size()) + " weights for " +
                                std::to_string(blocks.size()) + " cases");
  if (blocks.empty()) {
    out.resize(0, 0);
    return;
  }
  out.setZero(blocks.front().rows(), blocks.front().cols());
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    const double w = weights(static_cast<Eigen::Index>(k));
    if (w != 0.0) out.noalias() += w * blocks[k];
  }
}

}  // namespace flexbody::runtime
