#pragma once
// What a run records of a scene at a time (simulation.cpp): an output's columns and values, the monitors' row, and
// the angular momentum the conservation check watches. Internal to flexbody::scene.

#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/scene/scene.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace flexbody::scene {

/// The column names (with units) of output `s`, in the order values_of gives them.
[[nodiscard]] std::vector<std::string> columns_of(const Scene& scene, const Sensor& s);
/// Output `s`'s values at the integrator's state.
[[nodiscard]] Eigen::VectorXd values_of(const Scene& scene, const Sensor& s, const runtime::GeneralizedAlpha& integrator);

/// The monitors' columns: energies, the largest ‖AᵀA − I‖_F, the largest Tisserand and joint residuals, Newton
/// iterations.
[[nodiscard]] const std::vector<std::string>& monitor_columns();
[[nodiscard]] Eigen::VectorXd monitor_values(const Scene& scene, const runtime::GeneralizedAlpha& integrator);

/// The angular momentum about the system's centre of mass [kg m²/s], and the sum of its terms' magnitudes (the scale
/// its round-off is relative to).
struct AngularMomentum {
  Eigen::Vector3d value;
  double terms = 0.0;
};
[[nodiscard]] AngularMomentum angular_momentum(const runtime::System& system, const Eigen::VectorXd& q,
                                               const Eigen::VectorXd& v);

}  // namespace flexbody::scene
