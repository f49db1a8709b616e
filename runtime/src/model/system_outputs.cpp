// System: what a run reports: joint reactions and the energies.
#include "system_impl.hpp"

#include "../kernels/rotation.hpp"

#include <Eigen/Geometry>

namespace flexbody::runtime {

using detail::euler_global_velocity_matrix;

JointReaction System::Impl::joint_reaction(std::size_t joint, double t, const Eigen::VectorXd& q,
                                           const Eigen::VectorXd& lambda) const {
  const Joint& j = joints_.at(joint);
  if (j.first.body == kGround)
    throw std::invalid_argument("joint '" + j.name + "': its reaction is reported on the first marker's body, which is ground");
  const Eigen::VectorXd q1 = body_coordinates(q, j.first.body);
  const JointEvaluation e = evaluate_joint(j, t, q1, body_coordinates(q, j.second.body));
  const Eigen::VectorXd generalized = -e.jacobian_first.transpose() * lambda.segment(joint_row(joint), j.rows());
  return wrench(bodies_[static_cast<std::size_t>(j.first.body)], q1, generalized, marker_position(j.first, q1));
}

JointReaction System::Impl::wrench(const Body& b, const VectorRef& q_b, const Eigen::VectorXd& g,
                                   const Eigen::Vector3d& point) {
  JointReaction w;
  w.force = g.head<3>();
  // The moment about τ: the virtual work of a rigid rotation δθ of the whole body.
  Eigen::Vector3d about_tau = Eigen::Vector3d::Zero();
  if (b.model.floating()) {  // δp = ½ E(p)ᵀ δθ, η unchanged by a rigid rotation
    about_tau = 0.5 * euler_global_velocity_matrix(q_b.segment<4>(3)) * g.segment<4>(3);
  } else {
    for (Eigen::Index k = 1; k < q_b.size() / 3; ++k)  // the columns a_j of A, then the fields ξ_f: 3-blocks after τ
      about_tau += q_b.segment<3>(3 * k).cross(g.segment<3>(3 * k));
  }
  w.moment = about_tau - (point - q_b.head<3>()).cross(w.force);
  return w;
}

Energies System::Impl::energies(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const {
  Energies e;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    const auto q_b = q.segment(b.offset, n);
    const auto v_b = v.segment(b.offset, n);
    if (b.model.floating()) {  // gravity: −g · (m τ + A S(η)), the deformed centre of mass
      const FfrfModel& ff = *b.model.floating_frame;
      e.kinetic += ffrf_kinetic_energy(ff, q_b, v_b);
      e.elastic += ffrf_elastic_energy(ff, q_b);
      e.gravity -= gravity_.dot(ff.mass * q_b.head<3>() + euler_rotation(q_b.segment<4>(3)) * ffrf_first_moment(ff, q_b));
      continue;
    }
    e.kinetic += 0.5 * v_b.dot(mass_times(b.model, v_b));  // T = ½ v_bᵀ (G ⊗ I3) v_b
    for (Eigen::Index k = 0; k < n / 3; ++k) e.gravity -= b.model.g_border(0, k) * gravity_.dot(q_b.segment<3>(3 * k));
    if (!b.model.rigid()) e.elastic += body_elastic_forces(b.model, orientation_of(q_b), q_b.tail(n - 12)).energy;
  }
  for (const SpringDamper& s : springs_) {
    const double stretch = (marker_position(s.second, body_coordinates(q, s.second.body)) -
                            marker_position(s.first, body_coordinates(q, s.first.body))).norm() - s.rest_length;
    e.springs += 0.5 * s.stiffness * stretch * stretch;
  }
  return e;
}

}  // namespace flexbody::runtime
