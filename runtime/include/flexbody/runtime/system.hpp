#pragma once
// flexbody/runtime/system.hpp: a multibody system of improved-GCMS bodies (flexible or rigid: one code path),
// joints and forces, as the index-3 DAE the integrator solves (Zwölfer & Gerstmayr 2023, Eqs. 85-89):
//
//   M q̈ + ∂U/∂q + Φ_qᵀ λ = Q(t, q, q̇),   Φ(q, t) = 0,   M = diag(G_b ⊗ I3) constant.
//
// Coordinates are stacked body by body, q_b = [τ; a; ξ] (12 + 3 n_f). Constraint rows: per body its reference
// conditions (6 orthogonality rows; 3 rotational Tisserand rows if it is flexible; 3 translational Tisserand rows
// if its fields are not M-orthogonal to translations, as in the full-order reference), then every joint's rows.
//
// A body may instead move in floating-frame coordinates q_b = [τ; p; η] (7 + n_m, ffrf_dynamics.hpp): its mass
// matrix M_b(q) then depends on q, its quadratic velocity vector is among the forces, and its one reference row is
// the Euler parameters' normalisation pᵀp = 1. The mass-matrix functions take q for that reason.

#include "flexbody/runtime/body_model.hpp"
#include "flexbody/runtime/ffrf_dynamics.hpp"
#include "flexbody/runtime/joint.hpp"
#include "flexbody/runtime/marker.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace flexbody::runtime {

/// A body's initial state. ξ and ξ̇ are in the global frame (ξ_f = A ξ̄_f); empty means zero.
struct BodyState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();          ///< τ: the centre of mass [m]
  Eigen::Matrix3d orientation = Eigen::Matrix3d::Identity();   ///< A
  Eigen::VectorXd xi;                                          ///< 3 n_f
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();          ///< τ̇ [m/s]
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< ω [rad/s], global: Ȧ = [ω]× A
  Eigen::VectorXd xi_dot;                                      ///< 3 n_f
  Eigen::VectorXd eta, eta_dot;  ///< a floating-frame body's modal coordinates and their rates (n_m); empty: zero
};

/// A force [N] in the global frame at a marker, as a function of time.
struct PointForce {
  Marker marker;
  std::function<Eigen::Vector3d(double)> force;
};

/// A torque [N m] in the global frame at a marker, as a function of time. It does work on the body's rotation and,
/// through the marker's small rotation θ̄ = R ξ̄, on its deformation: Q_A = ½ [T]× A, Q_ξ = Â Rᵀ Aᵀ T.
struct PointTorque {
  Marker marker;
  std::function<Eigen::Vector3d(double)> torque;
};

/// A linear spring-damper between two markers (either may be on ground): the force F = k (ℓ − ℓ0) + c ℓ̇ pulls
/// them together along the line between them. Its tangent enters the Newton matrix in full with the dense solve,
/// and in its rigid-coordinate blocks with the constant core (whose ξξ block is the body's constant; see
/// docs/limits.md).
struct SpringDamper {
  std::string name;
  Marker first, second;
  double stiffness = 0.0;    ///< k [N/m]
  double damping = 0.0;      ///< c [N s/m]
  double rest_length = 0.0;  ///< ℓ0 [m]
};

/// A joint's constraint row left out because it repeats other rows (System::remove_redundant_constraints).
struct RemovedConstraint {
  std::size_t joint;    ///< its index in System::joints()
  std::string name;     ///< the joint's name
  int row;              ///< the row of the joint type's equations (Joint::type_rows), from 0
  std::string meaning;  ///< what it stopped, in global terms at the time of removal: joint_row_meaning
  double gap = 0.0;     ///< its residual where it was removed: a length [m] for a gap row, else a direction's cosine
};

/// The wrench a joint applies to the body of its first marker, in world axes: the force [N] and the moment [N m]
/// about the marker's current point.
struct JointReaction {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
};

/// The linearisation of one spring-damper for the Newton matrix: with J = [−P_1, P_2] (P_i = ∂r_i/∂q_i, the markers'
/// position Jacobians, empty for ground) the stiffness is Jᵀ K J and the damping Jᵀ C J, K = k eeᵀ + (T/ℓ)(I − eeᵀ)
/// and C = c eeᵀ (e the unit vector from marker 1 to marker 2, T the tension).
struct SpringTangent {
  int first = kGround, second = kGround;  ///< the markers' bodies
  Eigen::MatrixXd p_first, p_second;      ///< P_1 (3 x n_1), P_2 (3 x n_2)
  Eigen::Matrix3d stiffness = Eigen::Matrix3d::Zero(), damping = Eigen::Matrix3d::Zero();
};

struct Energies {
  double kinetic = 0.0, elastic = 0.0, gravity = 0.0;  ///< [J]; gravity = −Σ m g·r_cm (zero at the origin)
  double springs = 0.0;                                ///< ½ k (ℓ − ℓ0)² of the spring-dampers [J]
  [[nodiscard]] double total() const { return kinetic + elastic + gravity + springs; }
};

/// The bodies, joints and forces of a scene, and the equations of motion's terms at (t, q, q̇, q̈).
/// Its const members evaluate into work storage the System keeps (per joint, per body, per spring), so that a Newton
/// iteration allocates nothing: no member, const or not, may run on one System from two threads at once.
class System {
 public:
  System();
  ~System();
  System(const System& other);  ///< a copy with its own work storage (the constant matrices stay shared)
  System& operator=(const System& other);
  /// A moved-from System holds nothing: it may only be assigned to or destroyed.
  System(System&&) noexcept;
  System& operator=(System&&) noexcept;

  /// Adds a body; returns its index. Throws std::invalid_argument for a state of the wrong size or a
  /// non-orthogonal orientation.
  int add_body(const std::string& name, BodyModel model, const BodyState& initial);
  void add_joint(Joint joint);
  void add_force(PointForce force);
  void add_torque(PointTorque torque);
  void add_spring(SpringDamper spring);
  void set_gravity(const Eigen::Vector3d& gravity);

  [[nodiscard]] int body_count() const;
  /// Body `body`'s model. The reference stays valid for the System's lifetime: adding bodies does not move the ones
  /// already added (a simulator may keep it, as fbsim's outputs and ParaView series do).
  [[nodiscard]] const BodyModel& model(int body) const;
  [[nodiscard]] const std::string& body_name(int body) const;
  [[nodiscard]] int body_index(const std::string& name) const;  ///< throws std::invalid_argument if unknown
  [[nodiscard]] Eigen::Index offset(int body) const;
  [[nodiscard]] const std::vector<Joint>& joints() const;
  [[nodiscard]] const std::vector<PointForce>& forces() const;
  [[nodiscard]] const std::vector<PointTorque>& torques() const;
  [[nodiscard]] const std::vector<SpringDamper>& springs() const;

  [[nodiscard]] Eigen::Index coordinate_count() const;
  [[nodiscard]] Eigen::Index constraint_count() const;
  [[nodiscard]] Eigen::VectorXd initial_coordinates() const;
  /// One body's slice of initial_coordinates() (empty for kGround), without forming the whole vector.
  [[nodiscard]] Eigen::VectorXd initial_body_coordinates(int body) const;
  /// Replaces every body's initial position, orientation and deformation by those of q (initial_assembly.hpp); the
  /// initial velocities stay. Throws std::invalid_argument for an orientation that is not a rotation to 1e-9.
  void set_initial_coordinates(const Eigen::VectorXd& q);
  [[nodiscard]] Eigen::VectorXd initial_velocities() const;
  /// The coordinates of one body (a copy); empty for kGround.
  [[nodiscard]] Eigen::VectorXd body_coordinates(const Eigen::VectorXd& q, int body) const;

  /// M(q) = diag(M_b): G_b ⊗ I3 for a GCMS body (constant), M_b(q) for a floating-frame one; dense (for the dense
  /// reference Newton solve and tests).
  [[nodiscard]] Eigen::MatrixXd mass_matrix(const Eigen::VectorXd& q) const;
  /// The same, sparse: what the consistent initial accelerations factorize with the constraint Jacobian.
  [[nodiscard]] Eigen::SparseMatrix<double> sparse_mass_matrix(const Eigen::VectorXd& q) const;
  /// M(q) x without forming M: per GCMS body (G ⊗ I3) x_b = vec(X_b G) with X_b the 3 x (4 + n_f) blocks of x_b, a
  /// third of the dense product's work.
  [[nodiscard]] Eigen::VectorXd mass_product(const Eigen::VectorXd& q, const Eigen::VectorXd& x) const;
  /// Q − ∂U/∂q − ∂R/∂q̇: gravity (G[:, 0] ⊗ g), point forces (∂r/∂qᵀ F), torques, spring-dampers, minus the
  /// elastic forces (Eqs. 86-87) and the bodies' structural damping (damping.hpp); for a floating-frame body also
  /// its quadratic velocity vector.
  [[nodiscard]] Eigen::VectorXd forces(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const;
  /// M(q) q̈ − forces(t, q, q̇) into `out` (resized to the coordinates): the Newton iteration's dynamic rows. A
  /// floating-frame body's part is one pass over its η-dependent invariants (ffrf_residual) in a workspace the
  /// System keeps per body, so this is not safe to call on one System from two threads at once.
  /// Without `with_prestress` the geometric stiffness's forces are left out (add_prestress_residual adds them).
  void dynamic_residual(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& qdd,
                        Eigen::VectorXd& out, bool with_prestress = true) const;
  /// ∂²U/∂q² of the GCMS bodies, dense (the applied forces here do not depend on q; the springs' tangents are
  /// spring_tangents(); floating-frame bodies have floating_frame_tangent()).
  [[nodiscard]] Eigen::MatrixXd stiffness(const Eigen::VectorXd& q) const;
  /// A floating-frame body's exact tangents (ffrf_dynamics.hpp) at the system's q, q̇ and q̈, for the Newton matrix.
  [[nodiscard]] FfrfTangent floating_frame_tangent(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                                   const Eigen::VectorXd& a) const;
  /// A body's orientation A at q (mat(a), or A(p) of a floating-frame body).
  [[nodiscard]] Eigen::Matrix3d orientation(int body, const Eigen::VectorXd& q) const;
  /// Its angular velocity ω [rad/s] in the global frame.
  [[nodiscard]] Eigen::Vector3d angular_velocity(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& v) const;
  /// The spring-dampers' tangents at (q, q̇), one per spring with a defined direction (coincident markers have none).
  [[nodiscard]] std::vector<SpringTangent> spring_tangents(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const;
  [[nodiscard]] Eigen::VectorXd constraints(double t, const Eigen::VectorXd& q) const;
  /// The same into `phi` (resized): with the System's per-joint work storage, no allocation once sizes are set.
  void constraints(double t, const Eigen::VectorXd& q, Eigen::VectorXd& phi) const;
  /// Φ_q, dense (tests and the dense reference Newton solve; O(m n) storage).
  [[nodiscard]] Eigen::MatrixXd constraint_jacobian(double t, const Eigen::VectorXd& q) const;
  /// Φ_q into `out`, sparse (m x n, column-major): each body's reference rows over its own coordinates and each
  /// joint's rows over its two bodies' coordinates, O(rows x body size) storage, linear in the scene. Every entry of
  /// these blocks is stored, zero or not, so the pattern depends on the scene only and a factorization of a matrix
  /// built from it can keep its symbolic analysis from step to step.
  void sparse_constraint_jacobian(double t, const Eigen::VectorXd& q, Eigen::SparseMatrix<double>& out) const;
  /// Φ_qᵀ μ without forming Φ_q (the reference rows in O(n_f) per body): what a Newton residual needs.
  [[nodiscard]] Eigen::VectorXd constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q,
                                                                      const Eigen::VectorXd& mu) const;
  /// Adds Φ_qᵀ μ to `out` (n), allocating nothing: the Newton iteration's residual and position correction.
  void add_constraint_jacobian_transpose_product(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                                                 Eigen::VectorXd& out) const;
  /// Φ_q v without forming Φ_q (the reference rows in O(n_f) per body): the velocity constraints Φ_q q̇ + Φ_t.
  [[nodiscard]] Eigen::VectorXd constraint_jacobian_product(double t, const Eigen::VectorXd& q,
                                                            const Eigen::VectorXd& v) const;
  /// Φ and Φ_q v in one pass, each joint evaluated once (an iteration of the stabilised index-2 form needs both).
  void constraints_and_rates(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, Eigen::VectorXd& phi,
                             Eigen::VectorXd& rate) const;
  /// Φ_t: zero but in the angle rows of driven joints (driven_row_time_derivative: exact with a joint's angle_rate,
  /// else φ differenced over a step relative to `time_scale` [s], a time over which φ turns by little, such as the
  /// integrator's step).
  [[nodiscard]] Eigen::VectorXd constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale) const;
  /// Adds Φ_t to `out` (m), allocating nothing.
  void add_constraint_time_derivative(double t, const Eigen::VectorXd& q, double time_scale, Eigen::VectorXd& out) const;
  /// Σ_k λ_k ∂²Φ_k/∂q² of the reference conditions (exact) and of the joints (joint_hessian, over every coordinate).
  [[nodiscard]] Eigen::MatrixXd constraint_hessian(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& lambda) const;
  /// Adds Σ_j ∂(Φ_jᵀ λ_j)/∂q of the joints at time t (a driven joint's rows turn with φ(t)) to `out`, over the first counts[b] coordinates of each body b, placed at
  /// rows and columns offsets[b] + those (τ included: a prismatic row multiplies positions by a direction). By central
  /// differences of the joints' Jacobians, whose entries are low-degree polynomials in q (A(p) is quadratic, vec(A)
  /// enters linearly), so the differences are exact up to round-off and the cubic terms of a floating-frame marker:
  /// 2 counts joint evaluations per joint and side; spherical joints between GCMS bodies are linear and skipped. Direction rows (revolute, prismatic, fixed) are bilinear in
  /// the two bodies' orientations, and on a floating-frame body every marker row is nonlinear: without these terms
  /// Newton would converge linearly where joints carry large reactions. The dense Newton matrix uses it; the
  /// constant-core one leaves it out (newton_solvers.cpp: measured negligible there, and 20 % of a step).
  void add_joint_hessian(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& lambda, const std::vector<Eigen::Index>& offsets,
                         const std::vector<Eigen::Index>& counts, Eigen::MatrixXd& out) const;
  /// The first constraint row (in row order) that is linearly dependent on the rows before it at (t, q), or −1 if
  /// the rows are independent. A dependent row makes [M Φ_qᵀ; Φ_q 0] singular: its joint repeats what earlier
  /// constraints already impose (two revolute joints on one axis, a fixed joint plus a spherical one, ...).
  [[nodiscard]] Eigen::Index first_redundant_constraint(double t, const Eigen::VectorXd& q) const;
  /// Leaves out every joint row that is linearly dependent on the rows before it at (t, q), as Adams removes
  /// redundant constraints: a planar linkage of revolute joints in 3D (a four-bar repeats three of its twenty rows:
  /// the translation normal to its plane and the two tilts of its axes), two hinges on one axis. The later joint
  /// gives way (the rows are scanned in the order the joints were added). Returns what was left out (empty for
  /// independent rows); the joints' rows() and the row offsets change accordingly. The constraints the removed rows
  /// repeat carry their reactions: the removed rows' reaction components are reported by the joints they repeat,
  /// and a joint with removed rows reports none along them (Adams's convention). The test is at (t, q): rows that
  /// are dependent only in that configuration (a linkage at a dead point) are removed too, so call it with the
  /// assembled initial coordinates (runtime::initial_assembly refuses removed rows that the closed loop leaves off by
  /// more than its tolerance), and before a GeneralizedAlpha is built on the system: the row count changes. Rows once
  /// removed stay removed. Throws std::invalid_argument when a body's own reference rows are dependent, or a driven
  /// joint's angle row is (leaving it out would drop the drive).
  std::vector<RemovedConstraint> remove_redundant_constraints(double t, const Eigen::VectorXd& q);
  /// What constraint row k is: "body 'bar': orthogonality", "body 'bar': Tisserand", "joint 'pivot'", "body 'bar':
  /// normalisation of the Euler parameters".
  [[nodiscard]] std::string constraint_name(Eigen::Index row) const;
  /// The reaction of joint j on its first marker's body for multipliers λ (all rows, as the integrator holds them):
  /// the joint's generalized force Q = −Φ_qᵀλ on that body, reduced to the marker's point. The force is Q_τ; the
  /// moment about τ is Σ_j a_j × Q_a_j + Σ_f ξ_f × Q_ξ_f (the virtual work of a rigid rotation δθ of the whole
  /// deformed body, δa_j = δθ × a_j and δξ_f = δθ × ξ_f; on a floating-frame body δp = ½ E(p)ᵀ δθ with η unchanged,
  /// so the moment is ½ E(p) Q_p), moved to the marker's point p by −(p − τ) × F. Any joint
  /// type (for a prismatic joint too). For a joint between two markers of the same body it is the first marker's
  /// share (the wrench transmitted through the joint), not the net, which is zero. Throws std::invalid_argument if
  /// the first marker is on ground.
  [[nodiscard]] JointReaction joint_reaction(std::size_t joint, double t, const Eigen::VectorXd& q,
                                             const Eigen::VectorXd& lambda) const;
  /// The first constraint row of joint j (its rows follow in the order of joint.hpp).
  [[nodiscard]] Eigen::Index joint_row(std::size_t joint) const;
  /// The first constraint row of body b's reference conditions (6 orthogonality, then 3 rotational Tisserand if
  /// flexible, then 3 translational Tisserand if needed; 1 normalisation row for a floating-frame body).
  [[nodiscard]] Eigen::Index reference_row(int body) const;
  [[nodiscard]] Energies energies(const Eigen::VectorXd& q, const Eigen::VectorXd& v) const;

  /// Whether some body carries prestress cases (BodyModel::prestress): then set_prestress weights them.
  [[nodiscard]] bool has_prestress() const;
  /// Weights each prestressed body's geometric stiffness (prestress.hpp) by the loads at (t, q, q̇) with the joints'
  /// multipliers λ (all rows, as joint_reaction takes them): the body's spin in its own axes, and the force and the
  /// moment that the joints, point forces, torques and spring-dampers at each of its interfaces carry into it. The
  /// weights hold until the next call: forces() and dynamic_residual() add −K_g ξ̄ (a floating-frame body's −K_g η, and
  /// its tangent K_g), with K_g held fixed in their derivatives. The integrator calls this before every evaluation of
  /// the dynamic rows; without a call the weights are zero (no stiffening). Allocates nothing once sizes are set.
  void set_prestress(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& lambda,
                     double lambda_scale = 1.0) const;
  /// The Newton iteration's way to the same: the weights of set_prestress(t, q, q̇, scale μ), read from the joints'
  /// products Φ_qᵀ μ that the call add_constraint_jacobian_transpose_product(t, q, μ, ...) just before this one left
  /// in the System's work storage (so that each joint is evaluated once per iteration), and then the geometric
  /// stiffness's share of the dynamic rows, K_g ξ̄ / scale (what dynamic_residual(..., false) left out, scaled as the
  /// integrator scales those rows), added to `residual`.
  void add_prestress_residual(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& mu,
                              double scale, Eigen::VectorXd& residual) const;
  /// Why body b's geometric stiffness does not cover every load on it, or empty when it does: it has prestress cases
  /// (BodyModel::prestress), and every joint, point force, torque and spring-damper acts on it at one of its
  /// interfaces. A load elsewhere (a node, a point) is missing from its prestress. "it has no geometric stiffness",
  /// "joint 'hub' acts on it at beam/node 3, which is not an interface, so its prestress leaves that load out".
  [[nodiscard]] std::string prestress_gap(int body) const;
  /// Body b's current weights λ (one per case of its BodyModel::prestress; empty without).
  [[nodiscard]] const Eigen::VectorXd& prestress_weights(int body) const;

 private:
  class Impl;  // the bodies, joints, forces and work storage (runtime/src/model/system_impl.hpp)
  std::unique_ptr<Impl> impl_;
};

}  // namespace flexbody::runtime
