// System: the constraint rows (each GCMS body's reference conditions, Eqs. (77)-(78), then the joints), their
// Jacobian products, time derivative and curvature, and the rows' names.
#include "system_impl.hpp"

#include "../kernels/parallel.hpp"
#include "joint_rows.hpp"

#include "flexbody/runtime/reference_constraints.hpp"

#include <cmath>
#include <stdexcept>

namespace flexbody::runtime {

Eigen::Index System::Impl::reference_residuals(const Eigen::VectorXd& q, Eigen::VectorXd& phi) const {
  Eigen::Index row = 0;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    const auto q_b = q.segment(b.offset, n);
    if (b.model.floating()) {  // pᵀp − 1
      phi(row++) = q_b.segment<4>(3).squaredNorm() - 1.0;
      continue;
    }
    const Eigen::Matrix<double, 9, 1> ref = reference_residual(b.model.tisserand, orientation_of(q_b), q_b.tail(n - 12));
    phi.segment(row, std::min<Eigen::Index>(9, reference_rows(b))) = ref.head(std::min<Eigen::Index>(9, reference_rows(b)));
    if (reference_rows(b) == 12) {  // Eq. 77: Σ_f G[0, 4 + f] ξ_f
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (Eigen::Index f = 0; f < b.model.field_count(); ++f) sum += b.model.g_border(0, 4 + f) * q_b.segment<3>(12 + 3 * f);
      phi.segment<3>(row + 9) = sum;
    }
    row += reference_rows(b);
  }
  return row;
}

Eigen::Index System::Impl::reference_rates(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                           Eigen::VectorXd& rate) const {
  Eigen::Index row = 0;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count(), rows = std::min<Eigen::Index>(9, reference_rows(b));
    const auto q_b = q.segment(b.offset, n), v_b = v.segment(b.offset, n);
    if (b.model.floating()) {  // 2 pᵀṗ
      rate(row++) = 2.0 * q_b.segment<4>(3).dot(v_b.segment<4>(3));
      continue;
    }
    rate.segment(row, rows) = reference_jacobian_product(b.model.tisserand, orientation_of(q_b), q_b.tail(n - 12),
                                                         orientation_of(v_b), v_b.tail(n - 12))
                                  .head(rows);
    if (reference_rows(b) == 12) {
      rate.segment<3>(row + 9).setZero();
      for (Eigen::Index f = 0; f < b.model.field_count(); ++f)
        rate.segment<3>(row + 9) += b.model.g_border(0, 4 + f) * v_b.segment<3>(12 + 3 * f);
    }
    row += reference_rows(b);
  }
  return row;
}

const JointEvaluation& System::Impl::evaluated(std::size_t k, double t, const Eigen::VectorXd& q) const {
  const Joint& j = joints_[k];
  evaluate_joint(j, t, body_view(q, j.first.body), body_view(q, j.second.body), joint_work_[k]);
  return joint_work_[k];
}

Eigen::VectorXd System::Impl::constraints(double t, const Eigen::VectorXd& q) const {
  Eigen::VectorXd phi;
  constraints(t, q, phi);
  return phi;
}

void System::Impl::constraints(double t, const Eigen::VectorXd& q, Eigen::VectorXd& phi) const {
  phi.resize(constraint_count());
  reference_residuals(q, phi);
  // Each joint into its own rows, without its Jacobian (joint_rows.hpp).
  detail::for_each(static_cast<int>(joints_.size()), [&](int k) {
    const Joint& j = joints_[static_cast<std::size_t>(k)];
    detail::joint_residual(j, t, body_view(q, j.first.body), body_view(q, j.second.body),
                           phi.segment(joint_row(static_cast<std::size_t>(k)), j.rows()));
  });
}

void System::Impl::constraints_and_rates(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                         Eigen::VectorXd& phi, Eigen::VectorXd& rate) const {
  phi.resize(constraint_count());
  rate.resize(constraint_count());
  reference_residuals(q, phi);
  reference_rates(q, v, rate);
  // Each joint evaluated once for both, into its own rows, without its Jacobian (joint_rows.hpp).
  detail::for_each(static_cast<int>(joints_.size()), [&](int k) {
    const Joint& j = joints_[static_cast<std::size_t>(k)];
    const Eigen::Index row = joint_row(static_cast<std::size_t>(k));
    detail::joint_residual_and_rate(j, t, body_view(q, j.first.body), body_view(q, j.second.body),
                                    body_view(v, j.first.body), body_view(v, j.second.body), phi.segment(row, j.rows()),
                                    rate.segment(row, j.rows()));
  });
}

Eigen::MatrixXd System::Impl::constraint_jacobian(double t, const Eigen::VectorXd& q) const {
  Eigen::SparseMatrix<double> jac;
  sparse_constraint_jacobian(t, q, jac);
  return Eigen::MatrixXd(jac);
}

Eigen::VectorXd System::Impl::constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q,
                                                                    const Eigen::VectorXd& mu) const {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(coordinates_);
  add_constraint_jacobian_transpose_product(t, q, mu, out);
  return out;
}

void System::Impl::add_constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q,
                                                             const Eigen::VectorXd& mu, Eigen::VectorXd& out) const {
  Eigen::Index row = 0;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count(), rows = std::min<Eigen::Index>(9, reference_rows(b));
    const auto q_b = q.segment(b.offset, n);
    if (b.model.floating()) {
      out.segment<4>(b.offset + 3) += 2.0 * mu(row++) * q_b.segment<4>(3);
      continue;
    }
    Eigen::Matrix<double, 9, 1> mu_b = Eigen::Matrix<double, 9, 1>::Zero();
    mu_b.head(rows) = mu.segment(row, rows);
    b.gcms.reference.resize(n - 3);
    reference_jacobian_transpose_product(b.model.tisserand, orientation_of(q_b), q_b.tail(n - 12), mu_b, b.gcms.reference);
    out.segment(b.offset + 3, n - 3) += b.gcms.reference;
    if (reference_rows(b) == 12)
      for (Eigen::Index f = 0; f < b.model.field_count(); ++f)
        out.segment<3>(b.offset + 12 + 3 * f) += b.model.g_border(0, 4 + f) * mu.segment<3>(row + 9);
    row += reference_rows(b);
  }
  // Each joint's Φ_qᵀ μ without its Jacobian (joint_rows.hpp), into its own storage in parallel; the sums in joint
  // order, so that the result is the same for any thread count.
  const auto count = static_cast<int>(joints_.size());
  detail::for_each(count, [&](int k) {
    const auto ks = static_cast<std::size_t>(k);
    const Joint& j = joints_[ks];
    JointEvaluation& e = joint_work_[ks];
    detail::joint_transpose_product(j, t, body_view(q, j.first.body), body_view(q, j.second.body),
                                    mu.segment(joint_row(ks), j.rows()), e.product_first, e.product_second);
  });
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const Joint& j = joints_[k];
    const JointEvaluation& e = joint_work_[k];
    if (j.first.body != kGround) out.segment(offset(j.first.body), e.product_first.size()) += e.product_first;
    if (j.second.body != kGround) out.segment(offset(j.second.body), e.product_second.size()) += e.product_second;
  }
}

Eigen::VectorXd System::Impl::constraint_jacobian_product(double t, const Eigen::VectorXd& q,
                                                          const Eigen::VectorXd& v) const {
  Eigen::VectorXd phi, rate;
  constraints_and_rates(t, q, v, phi, rate);
  return rate;
}

Eigen::VectorXd System::Impl::constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale) const {
  Eigen::VectorXd rate = Eigen::VectorXd::Zero(constraint_count());
  add_constraint_time_derivative(t, q, time_scale, rate);
  return rate;
}

void System::Impl::add_constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale,
                                                  Eigen::VectorXd& out) const {
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const Joint& j = joints_[k];
    // The type's last row, the angle, is the only one that depends on t (never removed: remove_redundant_constraints).
    if (j.type != JointType::driven_revolute) continue;
    out(joint_row(k) + j.rows() - 1) += driven_row_time_derivative(j, t, time_scale, body_view(q, j.first.body),
                                                                   body_view(q, j.second.body), joint_work_[k].frames);
  }
}

Eigen::MatrixXd System::Impl::constraint_hessian(double t, const Eigen::VectorXd& q,
                                                 const Eigen::VectorXd& lambda) const {
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(coordinates_, coordinates_);
  Eigen::Index row = 0;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    const auto q_b = q.segment(b.offset, n);
    if (b.model.floating()) {  // ∂²(pᵀp)/∂p² = 2 I
      h.block<4, 4>(b.offset + 3, b.offset + 3).diagonal().setConstant(2.0 * lambda(row++));
      continue;
    }
    Eigen::Matrix<double, 9, 1> l = Eigen::Matrix<double, 9, 1>::Zero();
    l.head(std::min<Eigen::Index>(9, reference_rows(b))) = lambda.segment(row, std::min<Eigen::Index>(9, reference_rows(b)));
    h.block(b.offset + 3, b.offset + 3, n - 3, n - 3) =
        reference_hessian(b.model.tisserand, orientation_of(q_b), q_b.tail(n - 12), l);
    row += reference_rows(b);
  }
  std::vector<Eigen::Index> offsets, counts;
  for (const Body& b : bodies_) {
    offsets.push_back(b.offset);
    counts.push_back(b.model.coordinate_count());
  }
  add_joint_hessian(t, q, lambda, offsets, counts, h);
  return h;
}

void System::Impl::add_joint_hessian(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& lambda,
                                     const std::vector<Eigen::Index>& offsets, const std::vector<Eigen::Index>& counts,
                                     Eigen::MatrixXd& out) const {
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const Joint& j = joints_[k];
    if (j.rows() == 0) continue;  // every row removed as redundant
    const Eigen::VectorXd l = lambda.segment(joint_row(k), j.rows());
    if (!(l.cwiseAbs().maxCoeff() > 0.0)) continue;
    // A spherical joint between GCMS bodies (or ground) has rows linear in q: no curvature.
    if (j.type == JointType::spherical && !j.first.floating && !j.second.floating) continue;
    const int body[2] = {j.first.body, j.second.body};
    Eigen::VectorXd q_of[2];
    for (int s = 0; s < 2; ++s)
      if (body[s] != kGround) q_of[s] = body_coordinates(q, body[s]);
    // Φ_jᵀ λ on each side, over the kept coordinates.
    auto gradient = [&](Eigen::VectorXd (&g)[2]) {
      const JointEvaluation e = evaluate_joint(j, t, q_of[0], q_of[1]);
      for (int s = 0; s < 2; ++s)
        if (body[s] != kGround) g[s] = (s == 0 ? e.jacobian_first : e.jacobian_second).transpose() * l;
    };
    for (int s = 0; s < 2; ++s) {
      if (body[s] == kGround) continue;
      const auto bs = static_cast<std::size_t>(body[s]);
      for (Eigen::Index c = 0; c < counts[bs]; ++c) {
        const double x = q_of[s](c), step = 1e-6 * (1.0 + std::abs(x));
        Eigen::VectorXd plus[2], minus[2];
        q_of[s](c) = x + step;
        gradient(plus);
        q_of[s](c) = x - step;
        gradient(minus);
        q_of[s](c) = x;
        for (int r = 0; r < 2; ++r) {
          if (body[r] == kGround) continue;
          const auto br = static_cast<std::size_t>(body[r]);
          const Eigen::Index n = counts[br];
          out.block(offsets[br], offsets[bs] + c, n, 1) += (plus[r].head(n) - minus[r].head(n)) / (2.0 * step);
        }
      }
    }
  }
}

std::string System::Impl::constraint_name(Eigen::Index row) const {
  for (const Body& b : bodies_) {
    if (b.model.floating()) {
      if (row < 1) return "body '" + b.name + "': normalisation of the Euler parameters";
      row -= 1;
      continue;
    }
    if (row < 6) return "body '" + b.name + "': orthogonality of A (Eq. 79)";
    if (row < 9 && row < reference_rows(b)) return "body '" + b.name + "': rotational Tisserand condition (Eq. 78)";
    if (row < reference_rows(b)) return "body '" + b.name + "': translational Tisserand condition (Eq. 77)";
    row -= reference_rows(b);
  }
  for (const Joint& j : joints_) {
    if (row < j.rows()) return "joint '" + j.name + "'";
    row -= j.rows();
  }
  return "constraint " + std::to_string(row);
}

Eigen::Index System::Impl::reference_row(int body) const {
  return body == body_count() ? reference_total_ : bodies_.at(static_cast<std::size_t>(body)).reference_row;
}

Eigen::Index System::Impl::joint_row(std::size_t joint) const {
  return reference_total_ + (joint == joints_.size() ? joint_total_ : joint_start_.at(joint));
}

}  // namespace flexbody::runtime
