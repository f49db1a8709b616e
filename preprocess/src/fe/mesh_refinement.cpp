#include "flexbody/preprocess/mesh_refinement.hpp"

#include "flexbody/format/tet4_element.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace flexbody::preprocess {
namespace {

// The scale s_e = clamp(κ / w_e, finest, 1) with w_e = (η²_e)^(1/(2p+3)); an element without error keeps its size.
struct Scales {
  const Eigen::VectorXd& shares;
  Eigen::VectorXd weights;  // w_e
  int order;
  double finest;

  [[nodiscard]] double at(Eigen::Index e, double kappa) const {
    return weights(e) > 0.0 ? std::clamp(kappa / weights(e), finest, 1.0) : 1.0;
  }
  [[nodiscard]] double share(double kappa) const {  // Σ η²_e s_e^(2p): grows with κ
    double sum = 0.0;
    for (Eigen::Index e = 0; e < shares.size(); ++e) sum += shares(e) * std::pow(at(e, kappa), 2 * order);
    return sum;
  }
  [[nodiscard]] double elements(double kappa) const {  // Σ s_e^(-3): falls with κ
    double sum = 0.0;
    for (Eigen::Index e = 0; e < shares.size(); ++e) sum += std::pow(at(e, kappa), -3);
    return sum;
  }
};

// The κ in [low, high] where f(κ) crosses `value` (f monotone), by bisection on log κ to a relative 1e-12.
template <typename F>
double crossing(double low, double high, double value, bool increasing, const F& f) {
  for (int k = 0; k < 200 && high > low * (1.0 + 1e-12); ++k) {
    const double mid = std::sqrt(low * high);
    if ((f(mid) < value) == increasing)
      low = mid;
    else
      high = mid;
  }
  return increasing ? low : high;  // the side that keeps the target (share below, elements below)
}

}  // namespace

Eigen::VectorXd element_sizes(const TetMesh& mesh) {
  Eigen::VectorXd sizes(mesh.element_count());
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e) {
    Eigen::Matrix<double, 4, 3> corners;
    for (int a = 0; a < 4; ++a) corners.row(a) = mesh.nodes.row(mesh.tets(e, a));
    sizes(e) = std::cbrt(kTetrahedraPerCubedSize * std::abs(format::tet4_geometry(corners).volume));
  }
  return sizes;
}

RefinementPlan plan_refinement(const Eigen::VectorXd& sizes, const Eigen::VectorXd& shares,
                               const RefinementRequest& request) {
  const Eigen::Index n = sizes.size();
  if (shares.size() != n)
    throw std::invalid_argument(fmt::format("plan_refinement: {} sizes but {} shares", n, shares.size()));
  if (request.order != 1 && request.order != 2)
    throw std::invalid_argument(fmt::format("plan_refinement: element order {} (1 or 2)", request.order));
  if (!(request.target_share > 0.0) || !std::isfinite(request.target_share))
    throw std::invalid_argument(fmt::format("plan_refinement: target share {} is not positive", request.target_share));
  if (!(request.finest > 0.0 && request.finest <= 1.0))
    throw std::invalid_argument(fmt::format("plan_refinement: finest scale {} is outside (0, 1]", request.finest));
  if (!(request.max_elements >= static_cast<double>(n)))
    throw std::invalid_argument(fmt::format("plan_refinement: an element budget of {} is below the {} elements there are",
                                            request.max_elements, n));
  Scales scales{shares, Eigen::VectorXd(n), request.order, request.finest};
  double lightest = std::numeric_limits<double>::infinity(), heaviest = 0.0;
  for (Eigen::Index e = 0; e < n; ++e) {
    if (!(sizes(e) > 0.0) || !std::isfinite(sizes(e)))
      throw std::invalid_argument(fmt::format("plan_refinement: element {} has size {}", e, sizes(e)));
    if (!(shares(e) >= 0.0) || !std::isfinite(shares(e)))
      throw std::invalid_argument(fmt::format("plan_refinement: element {} has error share {}", e, shares(e)));
    scales.weights(e) = std::pow(shares(e), 1.0 / (2 * request.order + 3));
    if (scales.weights(e) > 0.0) {
      lightest = std::min(lightest, scales.weights(e));
      heaviest = std::max(heaviest, scales.weights(e));
    }
  }
  RefinementPlan plan;
  plan.sizes = sizes;
  plan.predicted_elements = static_cast<double>(n);
  plan.predicted_share = shares.sum();
  if (plan.predicted_share <= request.target_share || heaviest == 0.0) return plan;  // met already
  // κ from "every element with error at `finest`" (κ ≤ finest · min w) to "none refined" (κ ≥ max w).
  const double low = request.finest * lightest, high = heaviest;
  double kappa = scales.share(low) >= request.target_share
                     ? low  // out of reach in one pass: as far as `finest` allows
                     : crossing(low, high, request.target_share, true, [&](double k) { return scales.share(k); });
  if (scales.elements(kappa) > request.max_elements) {
    kappa = crossing(kappa, high, request.max_elements, false, [&](double k) { return scales.elements(k); });
    plan.budget_bound = true;
  }
  for (Eigen::Index e = 0; e < n; ++e) plan.sizes(e) = sizes(e) * scales.at(e, kappa);
  plan.predicted_share = scales.share(kappa);
  plan.predicted_elements = scales.elements(kappa);
  return plan;
}

}  // namespace flexbody::preprocess
