#include "body_measures.hpp"

#include "flexbody/runtime/ffrf_dynamics.hpp"
#include "flexbody/runtime/ffrf_model.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace flexbody::runtime::detail {

void coordinate_scales(const BodyModel& model, Eigen::Ref<Eigen::VectorXd> scales) {
  const double trace = model.g_border(1, 1) + model.g_border(2, 2) + model.g_border(3, 3);
  const double r = std::sqrt(std::max(trace, 0.0) / model.mass);
  scales.head(3).setConstant(r);
  if (model.floating()) {
    // A modal coordinate: each node's displacement in the mode is W_mᵀ Y(i, :)ᵀ.
    const FfrfModel& f = *model.floating_frame;
    scales.segment(3, 4).setConstant(0.5);
    const bool has_fields = model.fields.cols() == model.field_count() && model.fields.rows() == model.nodes.rows();
    Eigen::MatrixX3d u;  // every node's displacement in mode m (n_n x 3), Y W_m as two matrix products
    for (Eigen::Index m = 0; m < f.modes; ++m) {
      double largest = 0.0;
      if (has_fields && model.nodes.rows() > 0) {
        const auto w = f.shapes.middleCols<3>(3 * m);
        u.noalias() = model.fields * w.bottomRows(model.field_count());
        u.noalias() += model.nodes * w.middleRows<3>(1);
        u.rowwise() += w.row(0);
        largest = u.rowwise().norm().maxCoeff();
      }
      scales(7 + m) = largest > 0.0 ? r / largest : r * std::sqrt(model.mass / f.modal_mass(m, m));
    }
    return;
  }
  scales.segment(3, 9).setConstant(1.0);
  for (Eigen::Index f = 0; f < model.field_count(); ++f) {
    double scale = r;
    if (!model.sparse && model.fields.cols() == model.field_count() && model.fields.rows() > 0)
      scale = r / model.fields.col(f).cwiseAbs().maxCoeff();
    else if (!model.sparse)
      scale = r * std::sqrt(model.mass / model.mass_matrix(4 + f, 4 + f));
    scales.segment(12 + 3 * f, 3).setConstant(scale);
  }
}

double mesh_diagonal(const BodyModel& model) {
  const format::RowMatrixX3d& nodes = model.nodes;
  return nodes.rows() ? (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).norm() : 0.0;
}

double elastic_mass_norm_squared(const BodyModel& model, const VectorRef& q_b) {
  const Eigen::Index n = model.coordinate_count();
  if (model.floating()) return field_mass_norm_squared(model, ffrf_field_coordinates(*model.floating_frame, q_b));
  return field_mass_norm_squared(model, q_b.segment(12, n - 12));
}

ElasticMassNorm::ElasticMassNorm(const BodyModel& model) : model_(&model) {
  if (!model.floating()) return;
  // Γ_kl = c_kᵀ (G_ff ⊗ I3) c_l, by polarisation of the mass norm.
  const Eigen::Index modes = model.coordinate_count() - 7;
  Eigen::VectorXd q_b = Eigen::VectorXd::Zero(7 + modes);
  q_b(3) = 1.0;
  std::vector<Eigen::VectorXd> c(static_cast<std::size_t>(modes));
  for (Eigen::Index k = 0; k < modes; ++k) {
    q_b(7 + k) = 1.0;
    c[static_cast<std::size_t>(k)] = ffrf_field_coordinates(*model.floating_frame, q_b);
    q_b(7 + k) = 0.0;
  }
  gram_.resize(modes, modes);
  for (Eigen::Index k = 0; k < modes; ++k)
    for (Eigen::Index l = 0; l <= k; ++l) {
      const Eigen::VectorXd &ck = c[static_cast<std::size_t>(k)], &cl = c[static_cast<std::size_t>(l)];
      gram_(k, l) = gram_(l, k) =
          0.25 * (field_mass_norm_squared(model, ck + cl) - field_mass_norm_squared(model, ck - cl));
    }
}

double ElasticMassNorm::squared(const VectorRef& q_b) const {
  if (model_->rigid()) return 0.0;
  if (!model_->floating()) return elastic_mass_norm_squared(*model_, q_b);
  double squared = 0.0;
  const auto eta = q_b.segment(7, gram_.rows());
  for (Eigen::Index k = 0; k < gram_.rows(); ++k) squared += eta(k) * gram_.col(k).dot(eta);
  return squared;
}

}  // namespace flexbody::runtime::detail
