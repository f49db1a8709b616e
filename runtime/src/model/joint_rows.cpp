#include "joint_rows.hpp"

#include "marker_frame.hpp"

#include <cmath>

namespace flexbody::runtime::detail {

JointForm joint_form(const Joint& j, double t) {
  using Kind = JointForm::Kind;
  JointForm f;
  auto row = [&f](Kind kind, int a, int b) { f.rows[static_cast<std::size_t>(f.row_count++)] = {kind, a, b}; };
  auto gap_rows = [&] {
    for (int k = 0; k < 3; ++k) row(Kind::gap, k, 0);
  };
  // The three rows that keep two triads aligned, z1·y2, z1·x2, y1·x2, with first = {y1, z1}, second = {x2, y2, ...}.
  auto triad_rows = [&] {
    f.first = {j.triad_first.col(1), j.triad_first.col(2)};
    f.first_count = 2;
    f.second[0] = j.triad_second.col(0);
    f.second[1] = j.triad_second.col(1);
    row(Kind::dot, 1, 1);
    row(Kind::dot, 1, 0);
    row(Kind::dot, 0, 0);
  };
  switch (j.type) {
    case JointType::spherical: gap_rows(); break;
    case JointType::fixed:
      gap_rows();
      f.second_count = 2;
      triad_rows();
      break;
    case JointType::prismatic:  // the gap along the two normals at marker 2, then the triads
      f.second[2] = j.normal_a;
      f.second[3] = j.normal_b;
      f.second_count = 4;
      row(Kind::along, 2, 0);
      row(Kind::along, 3, 1);
      triad_rows();
      break;
    case JointType::revolute:
    case JointType::driven_revolute:
      gap_rows();
      f.first[0] = j.axis_first;
      f.second[0] = j.normal_a;
      f.second[1] = j.normal_b;
      f.first_count = 1;
      f.second_count = 2;
      row(Kind::dot, 0, 0);
      row(Kind::dot, 0, 1);
      if (j.type == JointType::driven_revolute) {
        // u1 · (cos φ n_b − sin φ n_a) = 0 holds when marker 1 has turned by φ about the axis.
        const double phi = j.angle(t);
        f.first[1] = j.reference_first;
        f.second[2] = std::cos(phi) * j.normal_b - std::sin(phi) * j.normal_a;
        f.first_count = 2;
        f.second_count = 3;
        row(Kind::dot, 1, 2);
      }
      break;
  }
  return f;
}

namespace {

// A joint's markers and the global values of its form's directions at (q1, q2).
struct Evaluated {
  JointForm form;
  MarkerFrame f1, f2;
  Eigen::Vector3d gap;
  std::array<Eigen::Vector3d, 2> u;  ///< first's directions, global
  std::array<Eigen::Vector3d, 4> w;  ///< second's

  Evaluated(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2) : form(joint_form(j, t)) {
    f1.evaluate(j.first, q1);
    f2.evaluate(j.second, q2);
    gap = f1.position() - f2.position();
    for (int k = 0; k < form.first_count; ++k) u[static_cast<std::size_t>(k)] = f1.direction(form.first[static_cast<std::size_t>(k)]);
    for (int k = 0; k < form.second_count; ++k) w[static_cast<std::size_t>(k)] = f2.direction(form.second[static_cast<std::size_t>(k)]);
  }

  [[nodiscard]] double residual(const Joint& j, const JointForm::Row& r) const {
    switch (r.kind) {
      case JointForm::Kind::gap: return gap(r.a);
      case JointForm::Kind::along: return gap.dot(w[static_cast<std::size_t>(r.a)]) - j.offset(r.b);
      case JointForm::Kind::dot: break;
    }
    return u[static_cast<std::size_t>(r.a)].dot(w[static_cast<std::size_t>(r.b)]);
  }
};

bool kept(const Joint& j, int type_row) { return ((j.removed >> type_row) & 1U) == 0; }

}  // namespace

void joint_residual(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2, Eigen::Ref<Eigen::VectorXd> residual) {
  const Evaluated e(j, t, q1, q2);
  for (int r = 0, out = 0; r < e.form.row_count; ++r)
    if (kept(j, r)) residual(out++) = e.residual(j, e.form.rows[static_cast<std::size_t>(r)]);
}

void joint_residual_and_rate(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2, const VectorRef& v1,
                             const VectorRef& v2, Eigen::Ref<Eigen::VectorXd> residual, Eigen::Ref<Eigen::VectorXd> rate) {
  Evaluated e(j, t, q1, q2);
  e.f1.set_rates(v1);
  e.f2.set_rates(v2);
  const Eigen::Vector3d gap_rate = e.f1.position_rate() - e.f2.position_rate();
  std::array<Eigen::Vector3d, 2> u_rate;
  std::array<Eigen::Vector3d, 4> w_rate;
  for (int k = 0; k < e.form.first_count; ++k)
    u_rate[static_cast<std::size_t>(k)] = e.f1.direction_rate(e.form.first[static_cast<std::size_t>(k)]);
  for (int k = 0; k < e.form.second_count; ++k)
    w_rate[static_cast<std::size_t>(k)] = e.f2.direction_rate(e.form.second[static_cast<std::size_t>(k)]);
  for (int r = 0, out = 0; r < e.form.row_count; ++r) {
    if (!kept(j, r)) continue;
    const JointForm::Row& row = e.form.rows[static_cast<std::size_t>(r)];
    const auto a = static_cast<std::size_t>(row.a), b = static_cast<std::size_t>(row.b);
    residual(out) = e.residual(j, row);
    switch (row.kind) {
      case JointForm::Kind::gap: rate(out) = gap_rate(row.a); break;
      case JointForm::Kind::along: rate(out) = gap_rate.dot(e.w[a]) + e.gap.dot(w_rate[a]); break;
      case JointForm::Kind::dot: rate(out) = u_rate[a].dot(e.w[b]) + e.u[a].dot(w_rate[b]); break;
    }
    ++out;
  }
}

void joint_transpose_product(const Joint& j, double t, const VectorRef& q1, const VectorRef& q2, const VectorRef& mu,
                             Eigen::VectorXd& out1, Eigen::VectorXd& out2) {
  const Evaluated e(j, t, q1, q2);
  // The rows' weights on each marker's position and directions (global): Φ_qᵀ μ = Σ J_rᵀ w_r + Σ J_dᵀ w_d per marker.
  Eigen::Vector3d w_r1 = Eigen::Vector3d::Zero(), w_r2 = Eigen::Vector3d::Zero();
  std::array<Eigen::Vector3d, 2> w_u;
  std::array<Eigen::Vector3d, 4> w_w;
  for (auto& x : w_u) x.setZero();
  for (auto& x : w_w) x.setZero();
  for (int r = 0, in = 0; r < e.form.row_count; ++r) {
    if (!kept(j, r)) continue;
    const double m = mu(in++);
    const JointForm::Row& row = e.form.rows[static_cast<std::size_t>(r)];
    const auto a = static_cast<std::size_t>(row.a), b = static_cast<std::size_t>(row.b);
    switch (row.kind) {
      case JointForm::Kind::gap:
        w_r1(row.a) += m;
        w_r2(row.a) -= m;
        break;
      case JointForm::Kind::along:
        w_r1 += m * e.w[a];
        w_r2 -= m * e.w[a];
        w_w[a] += m * e.gap;
        break;
      case JointForm::Kind::dot:
        w_u[a] += m * e.w[b];
        w_w[b] += m * e.u[a];
        break;
    }
  }
  out1.setZero(j.first.body == kGround ? 0 : q1.size());
  out2.setZero(j.second.body == kGround ? 0 : q2.size());
  e.f1.add_transpose_product(w_r1, e.form.first.data(), w_u.data(), e.form.first_count, out1);
  e.f2.add_transpose_product(w_r2, e.form.second.data(), w_w.data(), e.form.second_count, out2);
}

}  // namespace flexbody::runtime::detail
