#pragma once
// marker_frame.hpp (internal): what every body-fixed direction at one marker shares at one q_b (the body's rotation,
// the marker's small rotation R ξ̄ and its derivatives), so that a joint's two or three directions at a marker cost
// little more than one. marker_direction and marker_direction_jacobian (marker.hpp) are its one-direction form;
// evaluate_joint (joint.cpp) keeps a frame per marker. Without Jacobians (the second evaluate), the frame gives what the
// Newton iteration needs every iteration at O(n_b) cost without forming a Jacobian (joint_rows.hpp): the rates
// J q̇_b of the marker's position and directions, and the products J_rᵀ w + Σ_k J_dkᵀ w_k into the body's rows.

#include "flexbody/runtime/marker.hpp"

#include <Eigen/Core>

namespace flexbody::runtime::detail {

class MarkerFrame {
 public:
  /// The frame of marker `m` at its body's coordinates q_b (12 + 3 n_f, or 7 + n_m on a floating-frame body; ignored
  /// on ground). `storage` holds R_f Aᵀ of a GCMS marker's fields (3 x 3 n_f): the caller keeps it, so that a frame
  /// evaluated again for the same marker allocates nothing. Throws std::invalid_argument for a q_b of the wrong size.
  void evaluate(const Marker& m, const VectorRef& q_b, Eigen::MatrixXd& storage);
  /// The frame for directions, rates and products only (jacobian() then throws std::logic_error on a GCMS marker
  /// with fields): no storage. q_b must outlive the frame's use.
  void evaluate(const Marker& m, const VectorRef& q_b);
  /// A body-fixed direction d (body frame) in the global frame: A (d − [d]× R ξ̄), A(p) (d − [d]× Θ_c η), or d on
  /// ground.
  [[nodiscard]] Eigen::Vector3d direction(const Eigen::Vector3d& d) const;
  /// Its Jacobian ∂/∂q_b into `jac` (3 x q_b.size(); 3 x 0 on ground), resized only when its size differs.
  void jacobian(const Eigen::Vector3d& d, Eigen::MatrixXd& jac) const;

  /// The marker's position r (marker_position).
  [[nodiscard]] Eigen::Vector3d position() const;
  /// Sets the body's velocities q̇_b (same size as q_b; must outlive the frame's use) for the rates below, which
  /// throw std::logic_error without it.
  void set_rates(const VectorRef& v_b);
  /// ṙ = J_r q̇_b, and a direction's rate J_d q̇_b (zero on ground).
  [[nodiscard]] Eigen::Vector3d position_rate() const;
  [[nodiscard]] Eigen::Vector3d direction_rate(const Eigen::Vector3d& d) const;
  /// out += J_rᵀ w_r + Σ_k J_{d_k}ᵀ w_k over `count` directions d_k (body frame) with weights w_k (global); out is
  /// the body's q_b.size() rows. Nothing on ground.
  void add_transpose_product(const Eigen::Vector3d& w_r, const Eigen::Vector3d* d, const Eigen::Vector3d* w, int count,
                             Eigen::Ref<Eigen::VectorXd> out) const;

 private:
  void evaluate_values(const Marker& m, const VectorRef& q_b);  // kind, A, R ξ̄ (and the floating-frame terms)

  enum class Kind { ground, floating, gcms };
  Kind kind_ = Kind::ground;
  const Marker* marker_ = nullptr;
  Eigen::Index size_ = 0;                    ///< q_b.size()
  Eigen::Matrix3d rotation_;                 ///< A (GCMS) or A(p) (floating frame)
  Eigen::Vector4d euler_;                    ///< p (floating frame)
  Eigen::Vector3d small_ = Eigen::Vector3d::Zero();  ///< R ξ̄ = Σ_f R_f Aᵀ ξ_f (GCMS) or Θ_c η (floating frame)
  Eigen::Matrix<double, 3, 9> small_by_a_;   ///< ∂(R ξ̄)/∂A(i, j) in column 3j + i (GCMS with fields)
  const Eigen::MatrixXd* turned_ = nullptr;  ///< [R_1 Aᵀ, R_2 Aᵀ, ...] (GCMS with fields), in the caller's storage
  const double* q_ = nullptr;                ///< q_b
  Eigen::Vector3d local_;                    ///< X̄_c + Ψ_c η (floating frame)
  // The rates (set_rates): q̇_b, Ȧ (on a floating-frame body Σ_k ∂A/∂p_k ṗ_k), and d(R ξ̄)/dt or d(Θ_c η)/dt.
  const double* v_ = nullptr;
  Eigen::Matrix3d rotation_rate_;            ///< Ȧ
  Eigen::Vector3d small_rate_ = Eigen::Vector3d::Zero();
};

}  // namespace flexbody::runtime::detail
