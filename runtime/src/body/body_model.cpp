#include "flexbody/runtime/body_model.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

#include <stdexcept>

namespace flexbody::runtime {

Eigen::Index fields_of_first_modes(const format::Gcms& gcms, Eigen::Index k) {
  Eigen::Index n = 0;
  while (n < gcms.field_mode.size() && gcms.field_mode(n) < k) ++n;  // non-decreasing (SCHEMA.md)
  return n;
}

BodyModel rigid_body_model(double mass, const Eigen::Matrix3d& second_moment, const std::string& source) {
  if (!(mass > 0.0) || !std::isfinite(mass))
    throw std::invalid_argument(source + ": a rigid body's mass must be positive and finite, not " + std::to_string(mass));
  const double size = second_moment.cwiseAbs().maxCoeff();
  if (!second_moment.allFinite() || (second_moment - second_moment.transpose()).cwiseAbs().maxCoeff() > 1e-12 * size ||
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(second_moment, Eigen::EigenvaluesOnly).eigenvalues().minCoeff() <
          -1e-12 * size)
    throw std::invalid_argument(source + ": the second moment ∫ x xᵀ dm must be finite, symmetric and positive "
                                "semidefinite");
  BodyModel model;
  model.source = source;
  model.mass = mass;
  model.mass_matrix = Eigen::Matrix4d::Zero();
  model.mass_matrix(0, 0) = mass;
  model.mass_matrix.block<3, 3>(1, 1) = second_moment;
  model.stiffness.resize(0, 0);
  model.tisserand.resize(3, 0);
  model.fields.resize(0, 0);
  return model;
}

Eigen::VectorXd mass_times(const BodyModel& model, const Eigen::Ref<const Eigen::VectorXd>& x_b) {
  Eigen::VectorXd y(x_b.size());
  mass_times(model, x_b, y);
  return y;
}

void mass_times(const BodyModel& model, const Eigen::Ref<const Eigen::VectorXd>& x_b, Eigen::Ref<Eigen::VectorXd> y) {
  const Eigen::Index columns = 4 + model.field_count();
  if (x_b.size() != 3 * columns)
    throw std::invalid_argument(model.source + ": " + std::to_string(x_b.size()) + " coordinates for a body of " +
                                std::to_string(3 * columns));
  if (y.size() != x_b.size())
    throw std::invalid_argument(model.source + ": mass product into " + std::to_string(y.size()) + " entries, not " +
                                std::to_string(x_b.size()));
  if (model.unit_field_mass && !model.sparse) {  // G = [G_rr G_rf; G_rfᵀ I]: O(n_f) instead of O(n_f²)
    const Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>> x(x_b.data(), 3, columns);
    Eigen::Map<Eigen::Matrix<double, 3, Eigen::Dynamic>> out(y.data(), 3, columns);  // column c: 3-block c of y
    // Column by column of G (contiguous), fixed-size 4 x 3 blocks: for three rows neither GEMM nor a
    // coefficient-wise product over the strided rows of x pays off (measured: 4 % of a 20-mode step).
    Eigen::Matrix<double, 4, 3> rigid = Eigen::Matrix<double, 4, 3>::Zero();  // Σ_c G[0:4, c] x_cᵀ
    for (Eigen::Index c = 0; c < columns; ++c) rigid.noalias() += model.mass_matrix.col(c).head<4>() * x.col(c).transpose();
    out.leftCols<4>() = rigid.transpose();
    const Eigen::Matrix<double, 3, 4> x_r = x.leftCols<4>();
    for (Eigen::Index f = 4; f < columns; ++f) out.col(f) = x.col(f) + x_r * model.mass_matrix.col(f).head<4>();
    return;
  }
  using Strided = Eigen::InnerStride<3>;
  // (G ⊗ I3) x = per direction d, G times the d-th entries of the 3-blocks (GEMM's packing does not pay off for
  // three rows: measured twice the instructions).
  for (int d = 0; d < 3; ++d) {
    const Eigen::Map<const Eigen::VectorXd, 0, Strided> x_d(x_b.data() + d, columns);
    Eigen::Map<Eigen::VectorXd, 0, Strided> y_d(y.data() + d, columns);
    if (!model.sparse) {
      y_d.noalias() = model.mass_matrix * x_d;
      continue;
    }
    const SparseFieldBlocks& s = *model.sparse;  // [G_rr G_rf; G_fr M_s] with G_fr = G_rfᵀ
    const Eigen::VectorXd x_f = x_d.tail(columns - 4);
    y_d.head<4>().noalias() = s.border * Eigen::VectorXd(x_d);
    y_d.tail(columns - 4).noalias() = s.border.rightCols(columns - 4).transpose() * x_d.head<4>() + s.mass * x_f;
  }
}

double field_mass_norm_squared(const BodyModel& model, const Eigen::Ref<const Eigen::VectorXd>& xi) {
  if (model.unit_field_mass && !model.sparse) return xi.squaredNorm();
  const Eigen::Index n_f = model.field_count();
  double squared = 0.0;
  for (int d = 0; d < 3; ++d) {
    const Eigen::VectorXd x_d = Eigen::Map<const Eigen::VectorXd, 0, Eigen::InnerStride<3>>(xi.data() + d, n_f);
    squared += model.sparse ? x_d.dot(model.sparse->mass * x_d)
                            : x_d.dot(model.mass_matrix.bottomRightCorner(n_f, n_f) * x_d);
  }
  return squared;
}

Eigen::RowVectorXd field_row(const BodyModel& model, Eigen::Index node) {
  if (!model.sparse) return model.fields.row(node);
  Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(model.field_count());
  if (model.sparse->fields.rows() == 0) {  // Ῡ' = I: node i is field i
    row(node) = 1.0;
    return row;
  }
  for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(model.sparse->fields, node); it; ++it)
    row(it.col()) = it.value();
  return row;
}

ElasticForces body_elastic_forces(const BodyModel& model, const Eigen::Matrix3d& a, const VectorRef& xi) {
  return model.sparse ? elastic_forces(model.sparse->stiffness, a, xi) : elastic_forces(model.stiffness, a, xi);
}

ElasticTangent body_elastic_tangent(const BodyModel& model, const Eigen::Matrix3d& a, const VectorRef& xi,
                                    bool with_xi_xi) {
  return model.sparse ? elastic_tangent(model.sparse->stiffness, a, xi, with_xi_xi)
                      : elastic_tangent(model.stiffness, a, xi, with_xi_xi);
}

BodyModel make_body_model(const format::BodyData& body, std::optional<Eigen::Index> modes, const std::string& source,
                          bool with_recovery) {
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
  // The fields are M_s-orthonormal (SCHEMA.md; the reader refuses |G_ff − I| > 1e-10): G_ff = I up to the round-off
  // of their orthonormalisation (1.8e-15 in the bench bar's file). Making it exact, and G_fr = G_rfᵀ exactly, lets
  // every mass product skip the n_f-square block; no entry of G moves by more than 1e-10 (by about 1e-15 in
  // practice), far below any Newton tolerance.
  auto g_ff = model.mass_matrix.bottomRightCorner(n_f, n_f);
  if (n_f == 0 || (g_ff - Eigen::MatrixXd::Identity(n_f, n_f)).cwiseAbs().maxCoeff() <= 1e-10) {
    g_ff.setIdentity();
    model.mass_matrix.bottomLeftCorner(n_f, 4) = model.mass_matrix.topRightCorner(4, n_f).transpose();
    model.unit_field_mass = true;
  }
  model.tisserand = body.gcms.mass_matrix.block(1, 4, 3, n_f);
  model.fields = body.gcms.fields.leftCols(n_f);
  model.mode_coefficients = body.gcms.mode_coefficients.topLeftCorner(n_f, 3 * k);
  model.frequencies_hz = body.modes.frequencies_hz.head(k);
  if (k > 0) {  // the lowest elastic frequency the body can show: a clamped Craig-Bampton body's is its first clamped one
    model.lowest_frequency_hz = body.modes.frequencies_hz(0);
    const Eigen::VectorXd& clamped = body.modes.fixed_interface_frequencies_hz;
    if (clamped.size() > 0) model.lowest_frequency_hz = std::min(model.lowest_frequency_hz, clamped(0));
  }
  model.nodes = body.mesh.nodes;
  model.surface_triangles = body.mesh.surface_triangles;
  for (format::Interface i : body.interfaces) {
    i.y_row.conservativeResize(4 + n_f);
    i.rotation.conservativeResize(Eigen::NoChange, 3 * n_f);
    model.interfaces.push_back(std::move(i));
  }
  if (with_recovery)
    for (const format::RecoveryRegion& r : body.recovery)  // the first 3 n_f columns only, copied once
      model.recovery.push_back({r.name, r.nodes, r.stress_modes.leftCols(3 * n_f)});
  if (!body.geometric_stiffness.empty() && n_f > 0)
    model.prestress = std::make_shared<const Prestress>(make_prestress(body, n_f, model.interfaces));
  return model;
}

}  // namespace flexbody::runtime
