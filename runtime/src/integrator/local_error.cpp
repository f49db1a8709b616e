#include "local_error.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace flexbody::runtime::detail {

LocalError::LocalError(const System& system, const Eigen::VectorXd& reach, double coefficient,
                       const FieldPredictor& splitter)
    : coefficient_(coefficient), reach_(reach), weight_(reach.cwiseInverse()),
      field_frequencies_(splitter.frequencies()), fields_counted_(field_frequencies_.size(), 0) {
  for (int b = 0; b < system.body_count(); ++b) {
    const BodyModel& model = system.model(b);
    const Eigen::Index o = system.offset(b), n = model.coordinate_count();
    if (model.sparse)
      throw std::invalid_argument("generalized-alpha: error control measures a flexible body's deformation in the "
                                  "vibrations its step resolves, and body '" + system.body_name(b) + "' (the "
                                  "full-order model) has no modal split for that: give it a fixed step");
    if (model.floating()) {
      const FfrfModel& f = *model.floating_frame;
      Modes m{o + 7, Eigen::VectorXd(f.modes)};
      for (Eigen::Index k = 0; k < f.modes; ++k) m.omega2(k) = f.modal_stiffness(k, k) / f.modal_mass(k, k);
      modes_.push_back(std::move(m));
    } else {
      // τ and A by the rigid motion they make (frame_motion), not entry by entry: A's symmetric part is the body's
      // affine deformation, whose vibrations the step need not resolve.
      const Eigen::Index n_f = model.field_count();
      Frame frame;
      frame.offset = o;
      frame.fields = n_f;
      frame.border = model.mass_matrix.leftCols<4>();  // G(:, 0:4): ∫[1; X; Ῡ] [1, Xᵀ] dm
      frame.mass = model.mass;
      frame.first_moment = model.mass_matrix.block<3, 1>(1, 0);
      frame.inertia = model.mass_matrix.block<3, 3>(1, 1) - frame.first_moment * frame.first_moment.transpose() / model.mass;
      frame.radius = 1.0 / reach(o + 3);  // the rotation entries' reach is 1 / r
      frames_.push_back(std::move(frame));
      weight_.segment(o, 12).setZero();
      // A field the FieldPredictor splits is measured in its resolved components (FieldPredictor::displacement);
      // one it could not split is measured in every field.
      if (!model.rigid() && splitter.splits(o)) weight_.segment(o + 12, n - 12).setZero();
    }
  }
}

bool LocalError::counts(double omega2, double h, bool counted, bool first) {
  const double omega_h = std::sqrt(std::max(omega2, 0.0)) * h;
  if (first) return omega_h <= 1.0;
  return counted ? omega_h <= 2.0 : omega_h < 0.5;
}

void LocalError::set_step(double h) {
  for (const Modes& m : modes_)
    for (Eigen::Index k = 0; k < m.omega2.size(); ++k) {
      double& w = weight_(m.first + k);
      w = counts(m.omega2(k), h, w != 0.0, !stepped_) ? 1.0 / reach_(m.first + k) : 0.0;
    }
  for (std::size_t b = 0; b < field_frequencies_.size(); ++b) {  // ascending: the counted ones are the slowest
    const Eigen::VectorXd& omega2 = *field_frequencies_[b];
    Eigen::Index& counted = fields_counted_[b];
    Eigen::Index next = 0;
    while (next < omega2.size() && counts(omega2(next), h, next < counted, !stepped_)) ++next;
    counted = next;
  }
  stepped_ = true;
}

std::vector<double> LocalError::state() const {
  std::vector<double> out;
  for (const Modes& m : modes_)
    for (Eigen::Index k = 0; k < m.omega2.size(); ++k) out.push_back(weight_(m.first + k) != 0.0 ? 1.0 : 0.0);
  for (const Eigen::Index counted : fields_counted_) out.push_back(static_cast<double>(counted));
  return out;
}

void LocalError::restore(const std::vector<double>& state) {
  std::size_t expected = fields_counted_.size();
  for (const Modes& m : modes_) expected += static_cast<std::size_t>(m.omega2.size());
  if (state.size() != expected)
    throw std::invalid_argument("checkpoint: integrator.control.counted has " + std::to_string(state.size()) +
                                " entries, this system's error control " + std::to_string(expected));
  std::size_t i = 0;
  for (const Modes& m : modes_)
    for (Eigen::Index k = 0; k < m.omega2.size(); ++k)
      weight_(m.first + k) = state[i++] != 0.0 ? 1.0 / reach_(m.first + k) : 0.0;
  for (std::size_t b = 0; b < fields_counted_.size(); ++b) {
    const double counted = state[i++];
    if (!(counted >= 0.0 && counted <= static_cast<double>(field_frequencies_[b]->size())))
      throw std::invalid_argument("checkpoint: integrator.control.counted is out of range");
    fields_counted_[b] = static_cast<Eigen::Index>(counted);
  }
  stepped_ = true;
}

// The rigid motion that best fits (least squares over the mass) the displacement field x makes: a translation δc of
// the centre of mass and a rotation δθ about it, with r(X) = τ + A X + Σ_f Ῡ_f(X) ξ_f (Eq. (61)): ∫ x [1, Xᵀ] dm =
// D G(:, 0:4), D = [x_τ, x_A, x_ξ], and δθ = I_c⁻¹ ∫ y × x dm with y = A (X − c) and I_c the inertia about c.
double LocalError::frame_motion(const Frame& frame, const Eigen::VectorXd& q, const Eigen::VectorXd& x) const {
  const Eigen::Index o = frame.offset;
  const Eigen::Map<const Eigen::Matrix3Xd> d(x.data() + o, 3, 4 + frame.fields);
  const Eigen::Matrix<double, 3, 4> s = d * frame.border;  // [∫x dm, ∫x Xᵀ dm]
  const Eigen::Vector3d shift = s.col(0) / frame.mass;
  const Eigen::Map<const Eigen::Matrix3d> a(q.data() + o + 3);
  const Eigen::Matrix3d p = (s.rightCols<3>() - shift * frame.first_moment.transpose()) * a.transpose();  // ∫ x yᵀ dm
  const Eigen::Vector3d moment(p(2, 1) - p(1, 2), p(0, 2) - p(2, 0), p(1, 0) - p(0, 1));  // ∫ y × x dm
  const Eigen::Matrix3d j = a * frame.inertia * a.transpose();
  const Eigen::Matrix3d inertia = j.trace() * Eigen::Matrix3d::Identity() - j;
  const Eigen::Vector3d turn = inertia.ldlt().solve(moment);
  return std::max(shift.norm(), frame.radius * turn.norm());
}

void LocalError::estimate(const Eigen::VectorXd& a_from, const Eigen::VectorXd& a_to, double h, double span,
                          Eigen::VectorXd& out) const {
  out = (coefficient_ * h * h * h / span) * (a_to - a_from);
}

double LocalError::measure(const Eigen::VectorXd& q, const Eigen::VectorXd& e, FieldPredictor& fields) const {
  if (e.size() == 0) return 0.0;
  const double direct = e.cwiseProduct(weight_).cwiseAbs().maxCoeff();
  double split = fields.displacement(q, e, reach_, fields_counted_);
  for (const Frame& frame : frames_) split = std::max(split, frame_motion(frame, q, e));
  return std::max(direct, split);
}

}  // namespace flexbody::runtime::detail
