#include "flexbody/runtime/ffrf_dynamics.hpp"

#include "../kernels/rotation.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace flexbody::runtime {
namespace {

using Matrix34 = Eigen::Matrix<double, 3, 4>;
using Matrix44 = Eigen::Matrix<double, 4, 4>;

using detail::skew;

// axial(X)_i = ε_ijk X_jk: ∫ρ a × b = axial(∫ρ a bᵀ).
Eigen::Vector3d axial(const Eigen::Matrix3d& x) {
  return {x(1, 2) - x(2, 1), x(2, 0) - x(0, 2), x(0, 1) - x(1, 0)};
}

// ∂(Ḡ(p)ᵀ y)/∂p for a fixed y (4 x 4): Ḡᵀ y = [−e·y; e × y + e0 y].
Matrix44 body_velocity_transpose_derivative(const Eigen::Vector3d& y) {
  Matrix44 d = Matrix44::Zero();
  d.block<1, 3>(0, 1) = -y.transpose();
  d.block<3, 1>(1, 0) = y;
  d.block<3, 3>(1, 1) = -skew(y);
  return d;
}

// One body's coordinates, velocities and accelerations, split.
struct Split {
  Eigen::Vector3d tau_dd;
  Eigen::Vector4d p, p_d, p_dd;
  VectorRef eta, eta_d, eta_dd;
};

using Invariants = FfrfWorkspace;

// The invariants at η (ffrf_dynamics.hpp) into v: S, P_m, I_θθ, I_θf; no allocation once v is sized for n modes.
void invariants_into(const FfrfModel& f, const VectorRef& eta, Invariants& v) {
  const Eigen::Index n = f.modes;
  v.resize(n);
  v.s = f.first_moment + f.mode_first_moments * eta;
  // Σ_k η_k J2_mk for every m at once (3n x 3), then P_m = J1_mᵀ + its block m.
  v.stacked.setZero();
  for (Eigen::Index k = 0; k < n; ++k) v.stacked.noalias() += eta(k) * f.mode_products.middleCols<3>(3 * k);
  Eigen::Matrix3d j = f.second_moment;
  for (Eigen::Index m = 0; m < n; ++m) {
    const Eigen::Matrix3d p_m = f.mode_second_moments.middleCols<3>(3 * m).transpose() + v.stacked.middleRows<3>(3 * m);
    v.p.middleCols<3>(3 * m) = p_m;
    j += eta(m) * (f.mode_second_moments.middleCols<3>(3 * m) + p_m);  // J = J0 + Σ η_m (J1_m + P_m)
    v.i_tf.col(m) = -axial(p_m);                                      // ∫ρ ū × ψ_m
  }
  v.i_tt = j.trace() * Eigen::Matrix3d::Identity() - j;
}

Invariants invariants_at(const FfrfModel& f, const VectorRef& eta) {
  Invariants v;
  invariants_into(f, eta, v);
  return v;
}

// The body-frame quantities of one evaluation.
struct Frame {
  Eigen::Matrix3d a;
  Matrix34 g_bar;
  Eigen::Vector3d acc, alpha, omega;  // ā, ω̄̇, ω̄
};

Frame frame_of(const Eigen::Vector4d& p, const Eigen::Vector4d& p_d, const Eigen::Vector4d& p_dd,
               const Eigen::Vector3d& tau_dd, const Eigen::Vector3d& gravity) {
  Frame fr;
  fr.a = euler_rotation(p);
  fr.g_bar = euler_body_velocity_matrix(p);
  fr.acc = fr.a.transpose() * (tau_dd - gravity);
  fr.alpha = 2.0 * fr.g_bar * p_dd;
  fr.omega = 2.0 * fr.g_bar * p_d;
  return fr;
}

// F̄ = [F_τ; F_θ; F_η] (6 + n), body frame, without the elastic and damping forces, into out (sized 6 + n); uses
// v.gyro as scratch.
void body_forces_into(const FfrfModel& f, Invariants& v, const Frame& fr, const VectorRef& eta_d, const VectorRef& eta_dd,
                      Eigen::Ref<Eigen::VectorXd> out) {
  const Eigen::Index n = f.modes;
  const Eigen::Vector3d& w = fr.omega;
  const Eigen::Vector3d s_eta_d = f.mode_first_moments * eta_d;
  out.head<3>() = f.mass * fr.acc + fr.alpha.cross(v.s) + w.cross(w.cross(v.s)) + 2.0 * w.cross(s_eta_d) +
                  f.mode_first_moments * eta_dd;
  Eigen::Vector3d coriolis = Eigen::Vector3d::Zero();  // 2 (ω̄ Σ η̇_m tr P_m − Σ η̇_m P_m ω̄)
  for (Eigen::Index m = 0; m < n; ++m) {
    const auto p_m = v.p.middleCols<3>(3 * m);
    coriolis += 2.0 * eta_d(m) * (w * p_m.trace() - p_m * w);
  }
  out.segment<3>(3) = v.s.cross(fr.acc) + v.i_tt * fr.alpha + w.cross(v.i_tt * w) + coriolis + v.i_tf * eta_dd;
  // b_m = Σ_k η̇_k ∫ρ ψ_k × ψ_m (3 x n), for the gyroscopic term 2 ω̄ · b_m.
  v.gyro.setZero();
  for (Eigen::Index k = 0; k < n; ++k) v.gyro.noalias() += eta_d(k) * f.mode_cross.middleRows<3>(3 * k);
  const double w2 = w.squaredNorm();
  for (Eigen::Index m = 0; m < n; ++m) {
    const auto p_m = v.p.middleCols<3>(3 * m);
    out(6 + m) = f.mode_first_moments.col(m).dot(fr.acc) + v.i_tf.col(m).dot(fr.alpha) + w.dot(p_m * w) -
                 w2 * p_m.trace() + 2.0 * w.dot(v.gyro.col(m)) + f.modal_mass.row(m).dot(eta_dd);
  }
}

Eigen::VectorXd body_forces(const FfrfModel& f, Invariants& v, const Frame& fr, const VectorRef& eta_d,
                            const VectorRef& eta_dd) {
  Eigen::VectorXd out(6 + f.modes);
  body_forces_into(f, v, fr, eta_d, eta_dd, out);
  return out;
}

// R = T F̄ + [0; 0; K η + D η̇] into r (7 + n), T = diag(A, 2 Ḡᵀ, I).
void generalized_into(const FfrfModel& f, const Frame& fr, const Eigen::VectorXd& body, const VectorRef& eta,
                      const VectorRef* eta_d, Eigen::Ref<Eigen::VectorXd> r) {
  const Eigen::Index n = f.modes;
  r.head<3>() = fr.a * body.head<3>();
  r.segment<4>(3) = 2.0 * fr.g_bar.transpose() * body.segment<3>(3);
  r.tail(n) = body.tail(n);
  if (n > 0) {
    r.tail(n).noalias() += f.modal_stiffness * eta;
    if (eta_d && f.modal_damping.size() > 0) r.tail(n).noalias() += f.modal_damping * *eta_d;
  }
}

// The body-frame mass matrix M̄ = ∂F̄/∂[ā; ω̄̇; η̈] ((6 + n) square, symmetric).
Eigen::MatrixXd body_mass(const FfrfModel& f, const Invariants& v) {
  const Eigen::Index n = f.modes;
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(6 + n, 6 + n);
  m.topLeftCorner<3, 3>().diagonal().setConstant(f.mass);
  m.block<3, 3>(0, 3) = -skew(v.s);
  m.block<3, 3>(3, 0) = skew(v.s);
  m.block<3, 3>(3, 3) = v.i_tt;
  m.block(0, 6, 3, n) = f.mode_first_moments;
  m.block(3, 6, 3, n) = v.i_tf;
  m.block(6, 0, n, 3) = f.mode_first_moments.transpose();
  m.block(6, 3, n, 3) = v.i_tf.transpose();
  m.bottomRightCorner(n, n) = f.modal_mass;
  return m;
}

Eigen::Vector4d segment4(const VectorRef& x, Eigen::Index at) { return x.segment<4>(at); }

}  // namespace

Eigen::Matrix3d euler_rotation(const Eigen::Vector4d& p) {
  // (e0² − eᵀe) I + 2 e eᵀ + 2 e0 [e]×, entry by entry (the expression with its temporaries took 7 % of a step of 64
  // rigid links, where every marker evaluates it).
  const double e0 = p(0), e1 = p(1), e2 = p(2), e3 = p(3);
  const double d = e0 * e0 - e1 * e1 - e2 * e2 - e3 * e3;
  Eigen::Matrix3d a;
  a << d + 2.0 * e1 * e1, 2.0 * (e1 * e2 - e0 * e3), 2.0 * (e1 * e3 + e0 * e2),
       2.0 * (e1 * e2 + e0 * e3), d + 2.0 * e2 * e2, 2.0 * (e2 * e3 - e0 * e1),
       2.0 * (e1 * e3 - e0 * e2), 2.0 * (e2 * e3 + e0 * e1), d + 2.0 * e3 * e3;
  return a;
}

Eigen::Vector4d euler_parameters(const Eigen::Matrix3d& a) {
  Eigen::Quaterniond q(a);
  q.normalize();
  Eigen::Vector4d p(q.w(), q.x(), q.y(), q.z());
  return p(0) < 0.0 ? Eigen::Vector4d(-p) : p;
}

Eigen::Matrix<double, 3, 4> euler_rotation_derivative(const Eigen::Vector4d& p, const Eigen::Vector3d& x) {
  const double e0 = p(0);
  const Eigen::Vector3d e = p.tail<3>();
  Matrix34 d;
  d.col(0) = 2.0 * (e0 * x + e.cross(x));
  d.rightCols<3>() = 2.0 * (e.dot(x) * Eigen::Matrix3d::Identity() + e * x.transpose() - x * e.transpose() - e0 * skew(x));
  return d;
}

Eigen::Matrix<double, 3, 4> euler_body_velocity_matrix(const Eigen::Vector4d& p) {
  Matrix34 g;
  g.col(0) = -p.tail<3>();
  g.rightCols<3>() = -skew(p.tail<3>()) + p(0) * Eigen::Matrix3d::Identity();
  return g;
}

void FfrfWorkspace::resize(Eigen::Index n) {
  if (body.size() == 6 + n) return;
  stacked.resize(3 * n, 3);
  p.resize(3, 3 * n);
  i_tf.resize(3, n);
  gyro.resize(3, n);
  body.resize(6 + n);
}

void ffrf_residual(const FfrfModel& f, const VectorRef& q, const VectorRef& v, const VectorRef& a,
                   const Eigen::Vector3d& gravity, FfrfWorkspace& work, Eigen::Ref<Eigen::VectorXd> out) {
  const Eigen::Index n = f.modes;
  const Frame fr = frame_of(segment4(q, 3), segment4(v, 3), segment4(a, 3), a.head<3>(), gravity);
  invariants_into(f, q.tail(n), work);
  const VectorRef eta_d = v.tail(n);
  body_forces_into(f, work, fr, eta_d, a.tail(n), work.body);
  generalized_into(f, fr, work.body, q.tail(n), &eta_d, out);
}

Eigen::VectorXd ffrf_residual(const FfrfModel& f, const VectorRef& q, const VectorRef& v, const VectorRef& a,
                              const Eigen::Vector3d& gravity) {
  FfrfWorkspace work;
  Eigen::VectorXd out(7 + f.modes);
  ffrf_residual(f, q, v, a, gravity, work, out);
  return out;
}

void ffrf_mass_product(const FfrfModel& f, const VectorRef& q, const VectorRef& x, FfrfWorkspace& work,
                       Eigen::Ref<Eigen::VectorXd> out) {
  // M(q) x = T M̄ Tᵀ x: the residual's acceleration terms, F̄ at ω̄ = 0 and η̇ = 0 without gravity.
  const Eigen::Index n = f.modes;
  const Eigen::Vector4d zero4 = Eigen::Vector4d::Zero();
  const Frame fr = frame_of(segment4(q, 3), zero4, segment4(x, 3), x.head<3>(), Eigen::Vector3d::Zero());
  invariants_into(f, q.tail(n), work);
  const auto eta_dd = x.tail(n);
  work.body.head<3>() = f.mass * fr.acc + fr.alpha.cross(work.s) + f.mode_first_moments * eta_dd;
  work.body.segment<3>(3) = work.s.cross(fr.acc) + work.i_tt * fr.alpha + work.i_tf * eta_dd;
  for (Eigen::Index m = 0; m < n; ++m)
    work.body(6 + m) = f.mode_first_moments.col(m).dot(fr.acc) + work.i_tf.col(m).dot(fr.alpha) + f.modal_mass.row(m).dot(eta_dd);
  out.head<3>() = fr.a * work.body.head<3>();
  out.segment<4>(3) = 2.0 * fr.g_bar.transpose() * work.body.segment<3>(3);
  out.tail(n) = work.body.tail(n);
}

Eigen::VectorXd ffrf_mass_product(const FfrfModel& f, const VectorRef& q, const VectorRef& x) {
  FfrfWorkspace work;
  Eigen::VectorXd out(7 + f.modes);
  ffrf_mass_product(f, q, x, work, out);
  return out;
}

Eigen::VectorXd ffrf_forces(const FfrfModel& f, const VectorRef& q, const VectorRef& v, const Eigen::Vector3d& gravity) {
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(q.size());
  return -ffrf_residual(f, q, v, zero, gravity);
}

FfrfTangent ffrf_tangent(const FfrfModel& f, const VectorRef& q, const VectorRef& v, const VectorRef& a,
                         const Eigen::Vector3d& gravity) {
  const Eigen::Index n = f.modes, size = 7 + n;
  const Eigen::Vector4d p = segment4(q, 3), p_d = segment4(v, 3), p_dd = segment4(a, 3);
  const Frame fr = frame_of(p, p_d, p_dd, a.head<3>(), gravity);
  Invariants inv = invariants_at(f, q.tail(n));
  const VectorRef eta = q.tail(n), eta_d = v.tail(n), eta_dd = a.tail(n);
  const Eigen::VectorXd body = body_forces(f, inv, fr, eta_d, eta_dd);
  const Eigen::MatrixXd m_bar = body_mass(f, inv);
  const Eigen::Vector3d& w = fr.omega;
  const double w2 = w.squaredNorm();

  // ∂F̄/∂ω̄ (6 + n x 3).
  Eigen::MatrixXd d_omega(6 + n, 3);
  const Eigen::Vector3d s_eta_d = f.mode_first_moments * eta_d;
  d_omega.topRows<3>() = w.dot(inv.s) * Eigen::Matrix3d::Identity() + w * inv.s.transpose() -
                         2.0 * inv.s * w.transpose() - 2.0 * skew(s_eta_d);
  Eigen::Matrix3d p_v = Eigen::Matrix3d::Zero();
  double t_v = 0.0;
  for (Eigen::Index m = 0; m < n; ++m) {
    p_v += eta_d(m) * inv.p.middleCols<3>(3 * m);
    t_v += eta_d(m) * inv.p.middleCols<3>(3 * m).trace();
  }
  d_omega.middleRows<3>(3) = skew(w) * inv.i_tt - skew(inv.i_tt * w) + 2.0 * (t_v * Eigen::Matrix3d::Identity() - p_v);
  // ∂F̄/∂η̇ (6 + n x n), and the gyroscopic block 2 ω̄ · ∫ρ ψ_n × ψ_m.
  Eigen::MatrixXd d_eta_d(6 + n, n);
  d_eta_d.topRows<3>() = 2.0 * skew(w) * f.mode_first_moments;
  for (Eigen::Index m = 0; m < n; ++m) {
    const auto p_m = inv.p.middleCols<3>(3 * m);
    d_eta_d.block<3, 1>(3, m) = 2.0 * (w * p_m.trace() - p_m * w);
    Eigen::Vector3d b_m = Eigen::Vector3d::Zero();
    for (Eigen::Index k = 0; k < n; ++k) {
      const Eigen::Vector3d cross_km = axial(f.mode_products.block<3, 3>(3 * k, 3 * m));  // ∫ρ ψ_k × ψ_m
      d_eta_d(6 + m, k) = 2.0 * w.dot(cross_km);
      b_m += eta_d(k) * cross_km;
    }
    d_omega.row(6 + m) = w.transpose() * (p_m + p_m.transpose()) - 2.0 * p_m.trace() * w.transpose() + 2.0 * b_m.transpose();
  }
  // ∂F̄/∂η (6 + n x n) at fixed ā, ω̄̇, ω̄, η̇, η̈.
  Eigen::MatrixXd d_eta(6 + n, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Vector3d s_k = f.mode_first_moments.col(k);
    d_eta.block<3, 1>(0, k) = fr.alpha.cross(s_k) + w.cross(w.cross(s_k));
    const auto p_k = inv.p.middleCols<3>(3 * k);
    const Eigen::Matrix3d d_k = p_k + p_k.transpose();  // ∂J/∂η_k
    Eigen::Matrix3d rate = Eigen::Matrix3d::Zero(), accel = Eigen::Matrix3d::Zero();  // Σ_m η̇_m J2_mk, Σ_m η̈_m J2_mk
    for (Eigen::Index m = 0; m < n; ++m) {
      const auto j2_mk = f.mode_products.block<3, 3>(3 * m, 3 * k);
      rate += eta_d(m) * j2_mk;
      accel += eta_dd(m) * j2_mk;
      d_eta(6 + m, k) = -axial(j2_mk).dot(fr.alpha) + w.dot(j2_mk * w) - w2 * j2_mk.trace();
    }
    d_eta.block<3, 1>(3, k) = s_k.cross(fr.acc) + (d_k.trace() * Eigen::Matrix3d::Identity() - d_k) * fr.alpha -
                              w.cross(d_k * w) + 2.0 * (w * rate.trace() - rate * w) - axial(accel);
  }

  // Generalized: R = T F̄ + [0; 0; K η + D η̇], T = diag(A, 2 Ḡᵀ, I); ā = Aᵀ(τ̈ − g), ω̄̇ = 2 Ḡ p̈, ω̄ = 2 Ḡ ṗ.
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(size, 6 + n);
  t.topLeftCorner<3, 3>() = fr.a;
  t.block<4, 3>(3, 3) = 2.0 * fr.g_bar.transpose();
  t.bottomRightCorner(n, n).setIdentity();
  Eigen::MatrixXd t_inv = Eigen::MatrixXd::Zero(6 + n, size);  // ∂[ā; ω̄̇; η̈]/∂[τ̈; p̈; η̈] = Tᵀ
  t_inv = t.transpose();
  FfrfTangent out;
  out.mass = t * m_bar * t_inv;
  out.mass = 0.5 * (out.mass + out.mass.transpose()).eval();
  // ∂R/∂p: through A and Ḡ in T, and through ā, ω̄̇ and ω̄ in F̄.
  // ∂ā/∂p = ∂(A(p)ᵀ y)/∂p with y = τ̈ − g: Aᵀ(p) = A(p*), p* = (e0, −e).
  const Eigen::Vector4d conj(p(0), -p(1), -p(2), -p(3));
  Matrix34 d_acc = euler_rotation_derivative(conj, a.head<3>() - gravity);
  d_acc.rightCols<3>() *= -1.0;
  const Matrix34 d_alpha = -2.0 * euler_body_velocity_matrix(p_dd), d_w = -2.0 * euler_body_velocity_matrix(p_d);
  const Eigen::MatrixXd body_dp = m_bar.leftCols<3>() * d_acc + m_bar.middleCols<3>(3) * d_alpha + d_omega * d_w;
  out.stiffness = Eigen::MatrixXd::Zero(size, size);
  out.stiffness.block<3, 4>(0, 3) = euler_rotation_derivative(p, body.head<3>());
  out.stiffness.block<4, 4>(3, 3) = 2.0 * body_velocity_transpose_derivative(body.segment<3>(3));
  out.stiffness.middleCols<4>(3) += t * body_dp;
  out.stiffness.rightCols(n) = t * d_eta;
  out.stiffness.bottomRightCorner(n, n) += f.modal_stiffness;
  out.damping = Eigen::MatrixXd::Zero(size, size);
  out.damping.middleCols<4>(3) = t * (d_omega * (2.0 * fr.g_bar));
  out.damping.rightCols(n) = t * d_eta_d;
  if (f.modal_damping.size() > 0) out.damping.bottomRightCorner(n, n) += f.modal_damping;
  return out;
}

double ffrf_kinetic_energy(const FfrfModel& f, const VectorRef& q, const VectorRef& v) {
  return 0.5 * v.dot(ffrf_mass_product(f, q, v));
}

double ffrf_elastic_energy(const FfrfModel& f, const VectorRef& q) {
  const auto eta = q.tail(f.modes);
  return 0.5 * eta.dot(f.modal_stiffness * eta);
}

Eigen::Vector3d ffrf_first_moment(const FfrfModel& f, const VectorRef& q) {
  return f.first_moment + f.mode_first_moments * q.tail(f.modes);
}

Eigen::VectorXd ffrf_field_coordinates(const FfrfModel& f, const VectorRef& q) {
  const Eigen::Index n_f = f.shapes.rows() - 4;
  Eigen::VectorXd xi_bar(3 * n_f);
  Eigen::Map<Eigen::Matrix3Xd> blocks(xi_bar.data(), 3, n_f);  // column f: ξ̄_f = Σ_m η_m W_m(4 + f, :)ᵀ
  blocks.setZero();
  for (Eigen::Index m = 0; m < f.modes; ++m)
    blocks += q(7 + m) * f.shapes.block(4, 3 * m, n_f, 3).transpose();
  return xi_bar;
}

namespace {

// The rigid part of the modes at η: s = Σ η_m W_m(0, :)ᵀ and B = Σ η_m W_m(1:4, :)ᵀ.
void rigid_part(const FfrfModel& f, const VectorRef& eta, Eigen::Vector3d& s, Eigen::Matrix3d& b) {
  s.setZero();
  b.setZero();
  for (Eigen::Index m = 0; m < f.modes; ++m) {
    s += eta(m) * f.shapes.block<1, 3>(0, 3 * m).transpose();
    b += eta(m) * f.shapes.block<3, 3>(1, 3 * m).transpose();
  }
}

}  // namespace

Eigen::VectorXd gcms_coordinates(const BodyModel& model, const VectorRef& q) {
  if (!model.floating()) return q;
  const FfrfModel& f = *model.floating_frame;
  const Eigen::Index n_f = model.field_count();
  const Eigen::Matrix3d a = euler_rotation(q.segment<4>(3));
  Eigen::Vector3d s;
  Eigen::Matrix3d b;
  rigid_part(f, q.tail(f.modes), s, b);
  Eigen::VectorXd g(12 + 3 * n_f);
  g.head<3>() = q.head<3>() + a * s;
  const Eigen::Matrix3d a_g = a * (Eigen::Matrix3d::Identity() + b);
  g.segment<9>(3) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(a_g.data());
  const Eigen::VectorXd xi_bar = ffrf_field_coordinates(f, q);
  for (Eigen::Index k = 0; k < n_f; ++k) g.segment<3>(12 + 3 * k) = a * xi_bar.segment<3>(3 * k);
  return g;
}

Eigen::VectorXd gcms_velocities(const BodyModel& model, const VectorRef& q, const VectorRef& v) {
  if (!model.floating()) return v;
  const FfrfModel& f = *model.floating_frame;
  const Eigen::Index n_f = model.field_count();
  const Eigen::Vector4d p = q.segment<4>(3), p_d = v.segment<4>(3);
  const Eigen::Matrix3d a = euler_rotation(p);
  Eigen::Matrix3d a_d;  // Ȧ, column j: ∂(A e_j)/∂p ṗ
  for (int j = 0; j < 3; ++j) a_d.col(j) = euler_rotation_derivative(p, Eigen::Vector3d::Unit(j)) * p_d;
  Eigen::Vector3d s, s_d;
  Eigen::Matrix3d b, b_d;
  rigid_part(f, q.tail(f.modes), s, b);
  rigid_part(f, v.tail(f.modes), s_d, b_d);  // linear in η
  Eigen::VectorXd g(12 + 3 * n_f);
  g.head<3>() = v.head<3>() + a_d * s + a * s_d;
  const Eigen::Matrix3d a_g_d = a_d * (Eigen::Matrix3d::Identity() + b) + a * b_d;
  g.segment<9>(3) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(a_g_d.data());
  Eigen::VectorXd eta_d_as_q = q;
  eta_d_as_q.tail(f.modes) = v.tail(f.modes);
  const Eigen::VectorXd xi_bar = ffrf_field_coordinates(f, q), xi_bar_d = ffrf_field_coordinates(f, eta_d_as_q);
  for (Eigen::Index k = 0; k < n_f; ++k)
    g.segment<3>(12 + 3 * k) = a_d * xi_bar.segment<3>(3 * k) + a * xi_bar_d.segment<3>(3 * k);
  return g;
}

}  // namespace flexbody::runtime
