#pragma once
// System's bodies, joints, forces and work storage, and its evaluations (what each computes:
// flexbody/runtime/system.hpp). Defined in system.cpp, system_constraints.cpp, system_dynamics.cpp,
// system_outputs.cpp, system_prestress.cpp and constraint_jacobian.cpp; the installed class forwards to it
// (system_interface.cpp).

#include "flexbody/runtime/system.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <array>
#include <deque>
#include <memory>
#include <string>
#include <vector>

namespace flexbody::runtime {

namespace detail {
class PaddedMatrix;
class SharedMatrices;
class TripletAssembly;
}  // namespace detail

class System::Impl {
 public:
  int add_body(const std::string& name, BodyModel model, const BodyState& initial);
  void add_joint(Joint joint);
  void add_force(PointForce force);
  void add_torque(PointTorque torque);
  void add_spring(SpringDamper spring);
  void set_gravity(const Eigen::Vector3d& gravity) { gravity_ = gravity; }
  [[nodiscard]] int body_count() const { return static_cast<int>(bodies_.size()); }
  [[nodiscard]] const BodyModel& model(int body) const { return bodies_.at(static_cast<std::size_t>(body)).model; }
  [[nodiscard]] const std::string& body_name(int body) const { return bodies_.at(static_cast<std::size_t>(body)).name; }
  [[nodiscard]] int body_index(const std::string& name) const;
  [[nodiscard]] Eigen::Index offset(int body) const { return bodies_.at(static_cast<std::size_t>(body)).offset; }
  [[nodiscard]] const std::vector<Joint>& joints() const { return joints_; }
  [[nodiscard]] const std::vector<PointForce>& forces() const { return forces_; }
  [[nodiscard]] const std::vector<PointTorque>& torques() const { return torques_; }
  [[nodiscard]] const std::vector<SpringDamper>& springs() const { return springs_; }
  [[nodiscard]] Eigen::Index coordinate_count() const { return coordinates_; }
  [[nodiscard]] Eigen::Index constraint_count() const;
  [[nodiscard]] Eigen::VectorXd initial_coordinates() const;
  [[nodiscard]] Eigen::VectorXd initial_body_coordinates(int body) const;
  void set_initial_coordinates(const Eigen::VectorXd& q);
  [[nodiscard]] Eigen::VectorXd initial_velocities() const;
  [[nodiscard]] Eigen::VectorXd body_coordinates(const Eigen::VectorXd& q, int body) const;
  [[nodiscard]] Eigen::MatrixXd mass_matrix(const Eigen::VectorXd& q) const;
  [[nodiscard]] Eigen::SparseMatrix<double> sparse_mass_matrix(const Eigen::VectorXd& q) const;
  [[nodiscard]] Eigen::VectorXd mass_product(const Eigen::VectorXd& q, const Eigen::VectorXd& x) const;
  [[nodiscard]] Eigen::VectorXd forces(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const;
  void dynamic_residual(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& qdd,
                        Eigen::VectorXd& out, bool with_prestress = true) const;
  [[nodiscard]] Eigen::MatrixXd stiffness(const Eigen::VectorXd& q) const;
  [[nodiscard]] FfrfTangent floating_frame_tangent(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                                   const Eigen::VectorXd& a) const;
  [[nodiscard]] Eigen::Matrix3d orientation(int body, const Eigen::VectorXd& q) const;
  [[nodiscard]] Eigen::Vector3d angular_velocity(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const;
  [[nodiscard]] std::vector<SpringTangent> spring_tangents(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const;
  [[nodiscard]] Eigen::VectorXd constraints(double t, const Eigen::VectorXd& q) const;
  void constraints(double t, const Eigen::VectorXd& q, Eigen::VectorXd& phi) const;
  [[nodiscard]] Eigen::MatrixXd constraint_jacobian(double t, const Eigen::VectorXd& q) const;
  void sparse_constraint_jacobian(double t, const Eigen::VectorXd& q, Eigen::SparseMatrix<double>& out) const;
  [[nodiscard]] Eigen::VectorXd constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q,
                                                                      const Eigen::VectorXd& mu) const;
  void add_constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                                                 Eigen::VectorXd& out) const;
  [[nodiscard]] Eigen::VectorXd constraint_jacobian_product(double t, const Eigen::VectorXd& q,
                                                            const Eigen::VectorXd& v) const;
  void constraints_and_rates(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, Eigen::VectorXd& phi,
                             Eigen::VectorXd& rate) const;
  [[nodiscard]] Eigen::VectorXd constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale) const;
  void add_constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale,
                                      Eigen::VectorXd& out) const;
  [[nodiscard]] Eigen::MatrixXd constraint_hessian(double t, const Eigen::VectorXd& q,
                                                   const Eigen::VectorXd& lambda) const;
  void add_joint_hessian(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& lambda,
                         const std::vector<Eigen::Index>& offsets, const std::vector<Eigen::Index>& counts,
                         Eigen::MatrixXd& out) const;
  [[nodiscard]] Eigen::Index first_redundant_constraint(double t, const Eigen::VectorXd& q) const;
  std::vector<RemovedConstraint> remove_redundant_constraints(double t, const Eigen::VectorXd& q);
  [[nodiscard]] std::string constraint_name(Eigen::Index row) const;
  [[nodiscard]] JointReaction joint_reaction(std::size_t joint, double t, const Eigen::VectorXd& q,
                                             const Eigen::VectorXd& lambda) const;
  [[nodiscard]] Eigen::Index joint_row(std::size_t joint) const;
  [[nodiscard]] Eigen::Index reference_row(int body) const;
  [[nodiscard]] Energies energies(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const;
  [[nodiscard]] bool has_prestress() const { return prestressed_bodies_ > 0; }
  void set_prestress(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& lambda,
                     double lambda_scale = 1.0) const;
  void add_prestress_residual(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& mu,
                              double scale, Eigen::VectorXd& residual) const;
  [[nodiscard]] std::string prestress_gap(int body) const;
  [[nodiscard]] const Eigen::VectorXd& prestress_weights(int body) const {
    return bodies_.at(static_cast<std::size_t>(body)).prestress.weights;
  }

  struct Body;
  /// The reference rows' residuals and Φ_q v into the first rows of `phi` / `rate`; return how many rows.
  Eigen::Index reference_residuals(const Eigen::VectorXd& q, Eigen::VectorXd& phi) const;
  Eigen::Index reference_rates(const Eigen::VectorXd& q, const Eigen::VectorXd& v, Eigen::VectorXd& rate) const;
  /// Joint k evaluated at (t, q) in its work storage.
  const JointEvaluation& evaluated(std::size_t k, double t, const Eigen::VectorXd& q) const;
  /// A GCMS body's work storage for its forces and reference rows (Newton iterations allocate nothing).
  struct GcmsWorkspace {
    ElasticForces elastic;
    Eigen::VectorXd xi_bar, rate, damping_force, reference;
  };
  /// A prestressed body's weights and their sum, and scratch for the loads at its interfaces.
  struct PrestressState {
    Eigen::VectorXd weights;           ///< λ, one per case
    Eigen::Matrix3d orientation;       ///< A at the last update: body axes of the loads
    std::vector<InterfaceLoad> loads;  ///< per interface, body axes
    /// Σ λ_k Ĝ_k[4:, 4:] (n_f square, acting on ξ̄) on a GCMS body, Σ λ_k K_g,k (n_m square) on a floating-frame one.
    Eigen::MatrixXd matrix;
    Eigen::MatrixXd packed_cases;  ///< those blocks' lower triangles packed by column, one column per case
    Eigen::VectorXd packed;        ///< their weighted sum, packed
    Eigen::VectorXd xi_bar;        ///< ξ̄ = Âᵀ ξ
    Eigen::VectorXd generalized;   ///< a joint's generalized force on the body
    Eigen::VectorXd forces;        ///< (K_g ⊗ I3) ξ̄ (3 n_f) or K_g η (n_m)
    bool active = false;           ///< some λ_k ≠ 0
  };
  struct Body {
    std::string name;
    BodyModel model;
    BodyState initial;
    Eigen::Index offset = 0;
    Eigen::Index reference_rows = 0;  ///< 6 (rigid), 9, or 12 with the translational Tisserand rows; 1 (floating)
    Eigen::Index reference_row = 0;   ///< its first reference row
    /// K̂ as the runtime's product kernel reads it fastest (null for rigid and full-order bodies).
    std::shared_ptr<const detail::PaddedMatrix> stiffness;
    mutable FfrfWorkspace work;        ///< a floating-frame body's evaluation scratch (dynamic_residual)
    mutable GcmsWorkspace gcms;        ///< a GCMS body's (dynamic_residual, Φ_qᵀ μ)
    mutable PrestressState prestress;  ///< set_prestress's weights (used when the model has prestress cases)
  };
  /// set_prestress, with the joints' Φ_qᵀ λ evaluated here or (`evaluate_joints` false) as the last
  /// add_constraint_jacobian_transpose_product left it (at the same t, q and multipliers).
  void update_prestress(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& lambda,
                        double lambda_scale, bool evaluate_joints) const;
  /// Adds `sign` times the geometric stiffness's forces −K_g ξ̄ (−K_g η) of body b at q to its slice f_b, if its weights
  /// are set.
  void add_prestress_forces(const Body& b, const Eigen::VectorXd& q, Eigen::Ref<Eigen::VectorXd> f_b,
                            double sign) const;
  /// The wrench of a generalized force `g` on body b (coordinates q_b), world axes: its force g_τ and its moment about
  /// `point`, from the virtual work of a rigid translation and rotation of the whole body (joint_reaction, and the
  /// prestress's loads at interfaces).
  [[nodiscard]] static JointReaction wrench(const Body& b, const VectorRef& q_b, const Eigen::VectorXd& g,
                                            const Eigen::Vector3d& point);
  /// Spring k's force on its first marker (its negative acts on the second), global frame [N]: zero for coincident
  /// markers.
  [[nodiscard]] Eigen::Vector3d spring_force(std::size_t k, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const;
  int prestressed_bodies_ = 0;
  /// A GCMS body's gravity, elastic and damping forces, added to its slice f_b.
  void add_body_forces(const Body& b, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                       Eigen::Ref<Eigen::VectorXd> f_b, bool with_prestress = true) const;
  /// The applied forces, torques and spring-dampers, times `sign`, added to f.
  void add_applied_forces(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, double sign,
                          Eigen::VectorXd& f) const;
  [[nodiscard]] static Eigen::Index reference_rows(const Body& b) { return b.reference_rows; }
  /// Body `body`'s slice of q without a copy (empty for ground); valid while q is.
  [[nodiscard]] VectorRef body_view(const Eigen::VectorXd& q, int body) const;
  void check_marker(const Marker& m, const std::string& what) const;
  std::deque<Body> bodies_;  ///< a deque: add_body never moves a body, so references to its model stay valid
  std::vector<Joint> joints_;
  mutable std::vector<Eigen::Triplet<double>> jacobian_work_;  ///< sparse_constraint_jacobian's entries
  /// A cache that a copy of the System starts without: copies must not share mutable work storage (each may be used
  /// from its own thread).
  template <class T>
  struct OwnCache {
    std::shared_ptr<T> ptr;
    OwnCache() = default;
    OwnCache(const OwnCache&) {}
    OwnCache& operator=(const OwnCache&) {
      ptr.reset();
      return *this;
    }
    OwnCache(OwnCache&&) noexcept = default;
    OwnCache& operator=(OwnCache&&) noexcept = default;
    ~OwnCache() = default;
  };
  mutable OwnCache<detail::TripletAssembly> jacobian_assembly_;  ///< where the Jacobian's entries land in its matrix
  mutable std::vector<JointEvaluation> joint_work_;              ///< per joint: its last evaluation's storage
  mutable std::vector<std::array<Eigen::MatrixXd, 2>> spring_work_;  ///< per spring: its markers' position Jacobians
  std::vector<PointForce> forces_;
  std::vector<PointTorque> torques_;
  std::vector<SpringDamper> springs_;
  Eigen::Vector3d gravity_ = Eigen::Vector3d::Zero();
  Eigen::Index coordinates_ = 0;
  Eigen::Index reference_total_ = 0, joint_total_ = 0;  ///< the bodies' reference rows, and the joints' rows
  std::vector<Eigen::Index> joint_start_;               ///< per joint: its first row after the reference rows
  /// The bodies' constant matrices for the product kernel, each stored once (copies of a part share them; the
  /// matrices themselves are immutable and stay shared with a copy of the System, the index does not).
  OwnCache<detail::SharedMatrices> shared_matrices_;
};

}  // namespace flexbody::runtime
