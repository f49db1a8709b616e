#include "flexbody/runtime/ffrf_model.hpp"

#include "../kernels/rotation.hpp"

#include <Eigen/Geometry>

#include <stdexcept>

namespace flexbody::runtime {
namespace {

using detail::skew;

// Mode m's body-frame field coordinates c_m (3 n_f): c_m[3f + d] = W_m(4 + f, d).
Eigen::VectorXd field_coordinates(const Eigen::MatrixXd& w, Eigen::Index mode) {
  const Eigen::Index n_f = w.rows() - 4;
  Eigen::VectorXd c(3 * n_f);
  for (Eigen::Index f = 0; f < n_f; ++f)
    for (int d = 0; d < 3; ++d) c(3 * f + d) = w(4 + f, 3 * mode + d);
  return c;
}

}  // namespace

FfrfModel make_ffrf_model(const BodyModel& model, FloatingFrame frame, const std::string& interface) {
  if (model.sparse)
    throw std::invalid_argument(model.source + ": the full-order reference body has no modes for a floating frame");
  const Eigen::Index n_m = model.modes, n_f = model.field_count();
  if (model.mode_coefficients.rows() != n_f || model.mode_coefficients.cols() != 3 * n_m)
    throw std::invalid_argument(model.source + ": the mode coefficients do not match the fields kept");
  FfrfModel f;
  f.frame = frame;
  f.modes = n_m;
  f.mass = model.mass;
  const Eigen::MatrixXd& g = model.mass_matrix;  // G = Yᵀ M_s Y
  // Mean-axis modes: their field coordinates are the mode coefficients, no rigid part.
  f.shapes = Eigen::MatrixXd::Zero(4 + n_f, 3 * n_m);
  f.shapes.bottomRows(n_f) = model.mode_coefficients;
  f.rigid_rotations = Eigen::Matrix3Xd::Zero(3, n_m);
  if (frame == FloatingFrame::interface) {
    const format::Interface* found = nullptr;
    for (const format::Interface& i : model.interfaces)
      if (i.name == interface) found = &i;
    if (!found) {
      std::string known;
      for (const format::Interface& i : model.interfaces) known += (known.empty() ? "" : ", ") + i.name;
      throw std::invalid_argument(model.source + ": no interface '" + interface + "' to attach the floating frame to "
                                  "(interfaces: " + (known.empty() ? std::string("none") : known) + ")");
    }
    f.interface_name = interface;
    const Eigen::Vector3d center = found->y_row.segment<3>(1);  // X̄_c
    for (Eigen::Index m = 0; m < n_m; ++m) {
      const Eigen::VectorXd c = field_coordinates(f.shapes, m);
      const Eigen::Vector3d t = f.shapes.block(4, 3 * m, n_f, 3).transpose() * found->y_row.tail(n_f);  // t_m
      const Eigen::Vector3d theta = found->rotation * c;                                                 // θ_m
      // ψ_m − t_m − θ_m × (X̄ − X̄_c): constant part (θ_m × X̄_c − t_m), and −θ_m × X̄ = [θ_m]×ᵀ X̄, whose
      // coefficients on X̄'s columns (rows 1..3, u_d = Σ_j X̄_j W(1 + j, d)) are [θ_m]×.
      f.shapes.block<1, 3>(0, 3 * m) = (theta.cross(center) - t).transpose();
      f.shapes.block<3, 3>(1, 3 * m) = skew(theta);
      f.rigid_rotations.col(m) = -theta;
    }
  }
  f.first_moment = g.block<3, 1>(1, 0);
  f.second_moment = g.block<3, 3>(1, 1);
  const Eigen::MatrixXd gw = g * f.shapes;  // G W ((4 + n_f) x 3 n_m)
  f.mode_first_moments.resize(3, n_m);
  for (Eigen::Index m = 0; m < n_m; ++m) f.mode_first_moments.col(m) = gw.block<1, 3>(0, 3 * m).transpose();
  f.mode_second_moments = gw.middleRows<3>(1);
  f.mode_products = f.shapes.transpose() * gw;
  f.mode_products = 0.5 * (f.mode_products + f.mode_products.transpose()).eval();  // exactly symmetric
  f.mode_cross.resize(3 * n_m, n_m);
  for (Eigen::Index k = 0; k < n_m; ++k)
    for (Eigen::Index m = 0; m < n_m; ++m) {
      const Eigen::Matrix3d j2 = f.mode_products.block<3, 3>(3 * k, 3 * m);
      f.mode_cross.block<3, 1>(3 * k, m) = Eigen::Vector3d(j2(1, 2) - j2(2, 1), j2(2, 0) - j2(0, 2), j2(0, 1) - j2(1, 0));
    }
  f.modal_mass.resize(n_m, n_m);
  for (Eigen::Index m = 0; m < n_m; ++m)
    for (Eigen::Index n = 0; n < n_m; ++n) f.modal_mass(m, n) = f.mode_products.block<3, 3>(3 * m, 3 * n).trace();
  Eigen::MatrixXd c(3 * n_f, n_m);
  for (Eigen::Index m = 0; m < n_m; ++m) c.col(m) = field_coordinates(f.shapes, m);
  f.modal_stiffness = c.transpose() * model.stiffness * c;
  f.modal_stiffness = 0.5 * (f.modal_stiffness + f.modal_stiffness.transpose()).eval();
  if (model.prestress) {
    for (const Eigen::MatrixXd& g_k : model.prestress->matrices) {
      const Eigen::MatrixXd products = f.shapes.transpose() * (g_k * f.shapes);  // blocks (m, n): W_mᵀ Ĝ_k W_n
      Eigen::MatrixXd k_g(n_m, n_m);
      for (Eigen::Index m = 0; m < n_m; ++m)
        for (Eigen::Index n = 0; n < n_m; ++n) k_g(m, n) = products.block<3, 3>(3 * m, 3 * n).trace();
      f.prestress.push_back(0.5 * (k_g + k_g.transpose()));
    }
  }
  if (model.damping.size() > 0) {
    f.modal_damping = c.transpose() * model.damping * c;
    f.modal_damping = 0.5 * (f.modal_damping + f.modal_damping.transpose()).eval();
  }
  return f;
}

}  // namespace flexbody::runtime
