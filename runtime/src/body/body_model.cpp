#include "flexbody/runtime/body_model.hpp"

#include <stdexcept>

namespace flexbody::runtime {

Eigen::Index fields_of_first_modes(const format::Gcms& gcms, Eigen::Index k) {
  Eigen::Index n = 0;
  while (n < gcms.field_mode.size() && gcms.field_mode(n) < k) ++n;  // non-decreasing (SCHEMA.md)
  return n;
}

BodyModel make_body_model(const format::BodyData& body, std::optional<Eigen::Index> modes, const std::string& source) {
  const Eigen::Index available = body.modes.count();
  const Eigen::Index k = modes.value_or(available);
  if (k < 0 || k > available)
    throw std::invalid_argument(source + ": " + std::to_string(k) + " modes asked for, the file holds " +
                                std::to_string(available));
  const Eigen::Index n_f = fields_of_first_modes(body.gcms, k);
  BodyModel model;
  model.source = source;
  model.modes = k;
  model.mass = body.mass.mass;
  model.mass_matrix = body.gcms.mass_matrix.topLeftCorner(4 + n_f, 4 + n_f);
  model.stiffness = body.gcms.stiffness.topLeftCorner(3 * n_f, 3 * n_f);
  model.tisserand = body.gcms.mass_matrix.block(1, 4, 3, n_f);
  model.fields = body.gcms.fields.leftCols(n_f);
  model.mode_coefficients = body.gcms.mode_coefficients.topLeftCorner(n_f, 3 * k);
  model.frequencies_hz = body.modes.frequencies_hz.head(k);
  model.nodes = body.mesh.nodes;
  model.surface_triangles = body.mesh.surface_triangles;
  for (format::Interface i : body.interfaces) {
    i.y_row.conservativeResize(4 + n_f);
    i.rotation.conservativeResize(Eigen::NoChange, 3 * n_f);
    model.interfaces.push_back(std::move(i));
  }
  for (format::RecoveryRegion r : body.recovery) {
    r.stress_modes.conservativeResize(Eigen::NoChange, 3 * n_f);
    model.recovery.push_back(std::move(r));
  }
  return model;
}

}  // namespace flexbody::runtime
