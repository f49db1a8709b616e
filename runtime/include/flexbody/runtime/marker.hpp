#pragma once
// flexbody/runtime/marker.hpp: markers, the points and frames where joints and forces act (formulations.md, "The
// Method": constraints and markers). A marker's position is a row of Y: r = (yᵀ ⊗ I3) q_b = τ + A X̄_c + Σ_f y_f ξ_f,
// linear in q with a constant Jacobian. Its frame is A (I + [θ̄]×) with the small rotation θ̄ = R ξ̄ of its node set (ξ̄ =
// Âᵀ ξ), so a body-fixed direction d at the marker points along A (d + θ̄ × d) = A (d − [d]× R ξ̄).
//
// On a floating-frame body (ffrf_model.hpp, coordinates [τ; p; η]) the same marker is r = τ + A(p) (X̄_c + Ψ_c η)
// and θ̄ = Θ_c η, with Ψ_c and Θ_c its displacement and rotation per unit modal coordinate: nonlinear in q, so its
// Jacobians take the coordinates.

#include "flexbody/runtime/body_model.hpp"

#include <Eigen/Core>

#include <string>

namespace flexbody::runtime {

inline constexpr int kGround = -1;

struct Marker {
  int body = kGround;                   ///< index of the body in its System, or kGround
  std::string name;                     ///< for messages: "bar/tip", "ground"
  Eigen::VectorXd y;                    ///< 4 + n_f: the marker's row of Y
  Eigen::MatrixXd rotation;             ///< 3 x 3 n_f (R); zero columns for a point on a rigid body or a node
  Eigen::Vector3d ground_point = Eigen::Vector3d::Zero();  ///< the position of a ground marker [m]
  /// On a floating-frame body: Ψ_c and Θ_c (3 x n_m each, body frame) [kg^-1/2, kg^-1/2 m^-1]; empty otherwise.
  Eigen::Matrix3Xd modal_displacement, modal_rotation;
  bool floating = false;  ///< the marker's body moves in floating-frame coordinates
  /// The index of the body's interface (BodyModel::interfaces) this marker is, or −1: loads here prestress the body
  /// through that interface's cases (prestress.hpp).
  int interface = -1;
};

/// A body file's interface (rbe2/rbe3) of body `body` in a System. Throws std::invalid_argument naming the
/// interfaces there are if `name` is not one of them.
[[nodiscard]] Marker interface_marker(const BodyModel& model, int body, const std::string& body_name,
                                      const std::string& name);
/// A point fixed in the body frame (X̄, metres from the centre of mass): the rigid part of the motion only.
[[nodiscard]] Marker point_marker(const BodyModel& model, int body, const std::string& body_name,
                                  const Eigen::Vector3d& point);
/// One node of the mesh: its position follows the node's deformation; its frame is the body's.
[[nodiscard]] Marker node_marker(const BodyModel& model, int body, const std::string& body_name, Eigen::Index node);
/// A fixed point in space.
[[nodiscard]] Marker ground_marker(const Eigen::Vector3d& point);

/// The marker's position for the body coordinates q_b (12 + 3 n_f); a ground marker ignores q_b.
[[nodiscard]] Eigen::Vector3d marker_position(const Marker& m, const VectorRef& q_b);
/// ∂r/∂q_b (3 x BodyModel::coordinate_count()): yᵀ ⊗ I3 on a GCMS body (constant; q_b unused), [I, ∂(A ū_c)/∂p,
/// A Ψ_c] on a floating-frame body.
[[nodiscard]] Eigen::MatrixXd marker_position_jacobian(const Marker& m, const VectorRef& q_b);
/// The same into `jac`, resized only when its size differs (no allocation when reused for the same marker).
void marker_position_jacobian(const Marker& m, const VectorRef& q_b, Eigen::MatrixXd& jac);
/// A body-fixed direction d (body frame) at the marker, in the global frame: A (d − [d]× R ξ̄).
[[nodiscard]] Eigen::Vector3d marker_direction(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d);
/// Its Jacobian (3 x (12 + 3 n_f)); zero columns for τ.
[[nodiscard]] Eigen::MatrixXd marker_direction_jacobian(const Marker& m, const VectorRef& q_b,
                                                        const Eigen::Vector3d& d);
/// The same into `jac` (3 x 0 on ground), resized only when its size differs (a GCMS marker with fields allocates a
/// work buffer per call: joints keep one per marker, runtime/src/model/marker_frame.hpp).
void marker_direction_jacobian(const Marker& m, const VectorRef& q_b, const Eigen::Vector3d& d, Eigen::MatrixXd& jac);

/// The orientation A of the marker's body (identity for ground): mat(a), or A(p) on a floating-frame body.
[[nodiscard]] Eigen::Matrix3d marker_body_orientation(const Marker& m, const VectorRef& q_b);

/// A = mat(a) of GCMS body coordinates q_b.
[[nodiscard]] inline Eigen::Matrix3d orientation_of(const VectorRef& q_b) {
  return Eigen::Map<const Eigen::Matrix3d>(q_b.data() + 3);
}

}  // namespace flexbody::runtime
