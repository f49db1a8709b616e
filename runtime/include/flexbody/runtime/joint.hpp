#pragma once
// flexbody/runtime/joint.hpp: joints between two markers (either may be on ground) as algebraic constraints
// Φ(q, t) = 0 with exact Jacobians (FORMULATION.md section 4).
//
//   spherical        r_1 − r_2 = 0                                               3 rows
//   fixed            spherical, and the markers' frames keep their initial relative orientation   6 rows
//   revolute         spherical, and the axis at marker 1 stays perpendicular to two directions normal
//                    to the axis at marker 2                                      5 rows
//   prismatic        r_1 − r_2 keeps its initial components normal to the axis, frames as fixed   5 rows
//   driven revolute  revolute, and the angle about the axis follows φ(t) (φ(0) = 0: the initial state)   6 rows
//
// Directions are body-fixed at their marker and turn with it: A (I + [θ̄]×) d (marker.hpp). They are fixed in each
// body's frame from the global axis and the initial state when the joint is made, so the initial state satisfies
// every row (a spherical joint also needs r_1 = r_2 initially: the caller's scene must be assembled).

#include "flexbody/runtime/marker.hpp"

#include <Eigen/Core>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace flexbody::runtime {

enum class JointType { spherical, fixed, revolute, prismatic, driven_revolute };

struct Joint {
  std::string name;
  JointType type = JointType::spherical;
  Marker first, second;
  /// Unit vectors in the frame of each marker's body (global for ground): the axis at marker 1 and at marker 2,
  /// two normals at marker 2, and marker 1's normal that coincides with normal_a initially.
  Eigen::Vector3d axis_first = Eigen::Vector3d::UnitZ(), axis_second = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d normal_a = Eigen::Vector3d::UnitX(), normal_b = Eigen::Vector3d::UnitY();
  Eigen::Vector3d reference_first = Eigen::Vector3d::UnitX();
  /// Frames for fixed and prismatic joints: the global axes x, y, z in each body's frame initially.
  Eigen::Matrix3d triad_first = Eigen::Matrix3d::Identity(), triad_second = Eigen::Matrix3d::Identity();
  /// Prismatic: the initial components of r_1 − r_2 along normal_a and normal_b.
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
  /// Driven revolute: the angle about the axis [rad] as a function of time, φ(0) = 0.
  std::function<double(double)> angle;

  [[nodiscard]] int rows() const;
};

/// A joint assembled at the initial body coordinates q1, q2 (empty for ground): `axis` is global (revolute,
/// prismatic, driven revolute; ignored otherwise). Throws std::invalid_argument naming the joint for a zero axis
/// or markers apart for a joint that ties their positions.
[[nodiscard]] Joint make_joint(const std::string& name, JointType type, Marker first, Marker second,
                               const Eigen::Vector3d& axis, const VectorRef& q1, const VectorRef& q2,
                               std::function<double(double)> angle = {});

/// Residuals, and Jacobians with respect to each marker's body coordinates (rows x n_b; 0 columns for ground).
struct JointEvaluation {
  Eigen::VectorXd residual;
  Eigen::MatrixXd jacobian_first, jacobian_second;
  /// Work storage: the markers' position Jacobians and up to four direction Jacobians.
  Eigen::MatrixXd position_first, position_second;
  std::array<Eigen::MatrixXd, 4> directions;
};
[[nodiscard]] JointEvaluation evaluate_joint(const Joint& joint, double t, const VectorRef& q1,
                                             const VectorRef& q2);
/// The same into `out`: an evaluation reused for the same joint allocates nothing (the Newton iteration's
/// joints, System).
void evaluate_joint(const Joint& joint, double t, const VectorRef& q1, const VectorRef& q2, JointEvaluation& out);

}  // namespace flexbody::runtime
