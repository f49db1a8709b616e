#pragma once
// flexbody/runtime/scene_builder.hpp: a scene in code, named as a scene file names it. A body is placed by its input
// (CAD) frame, a marker is named by its body and an interface, a point or a node, and a joint by its type, its
// markers and its axis; the builder finds the bodies' indices and initial coordinates that System and make_joint
// take. fbsim's scene loader builds through it.
//
// \code
//   flexbody::runtime::System system;
//   flexbody::runtime::SceneBuilder scene(system);
//   flexbody::runtime::SceneBody arm;
//   arm.file = "bracket.fbh5";
//   arm.modes = 6;
//   scene.add_body("arm", arm);   // its input frame where the global one is
//   scene.add_joint("pivot", flexbody::runtime::JointType::revolute, scene.interface("arm", "bore_1"), {},
//                   Eigen::Vector3d::UnitZ());   // to ground, where bore_1 is now
// \endcode

#include "flexbody/runtime/joint.hpp"
#include "flexbody/runtime/marker.hpp"
#include "flexbody/runtime/scene_body.hpp"
#include "flexbody/runtime/system.hpp"

#include <Eigen/Core>

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace flexbody::runtime {

/// Where a body starts: its input (CAD) frame's origin and orientation, and its rigid velocities.
struct Placement {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();          ///< the input frame's origin [m]
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();      ///< the body's orientation
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();          ///< of the centre of mass [m/s]
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< [rad/s], global
};

/// A driven revolute joint's angle: the speed Ω reached smoothly over `ramp` seconds, φ̇ = Ω (1 − cos πt/T) / 2 for
/// t < T, then Ω (no jerk at the start: a step in speed would be an impulse).
struct JointDrive {
  double speed = 0.0;  ///< Ω [rad/s]
  double ramp = 0.0;   ///< T [s]; 0: at speed from the start
};
/// φ(t) [rad] and φ̇(t) [rad/s] of a drive (make_joint's angle and angle_rate).
[[nodiscard]] std::function<double(double)> drive_angle(const JointDrive& drive);
[[nodiscard]] std::function<double(double)> drive_angle_rate(const JointDrive& drive);

/// The time shape of an applied force or torque: a linear rise from 0 over `ramp` seconds, times sin(2π f t) when a
/// frequency f is given (fbsim's forces: ramp, frequency).
struct LoadShape {
  double ramp = 0.0;       ///< [s]; 0: the full load from the start
  double frequency = 0.0;  ///< f [Hz]; 0: constant after the ramp
};
/// Its factor at time t [1].
[[nodiscard]] std::function<double(double)> load_factor(const LoadShape& shape);

class SceneBuilder {
 public:
  /// Builds into `system`, which must outlive the builder. Bodies added to the system directly are found by name
  /// for interfaces, nodes and joints, but have no input frame here, so point() refuses them.
  explicit SceneBuilder(System& system) : system_(system) {}

  /// Adds a body whose input frame is placed as `placement` says; `input_center_of_mass` is its centre of mass in
  /// its input frame (a body file's mass.center_of_mass_input; zero for a model built about its centre of mass).
  /// Returns its index in the System. Throws std::invalid_argument for a name already used.
  int add_body(const std::string& name, BodyModel model, const Placement& placement = {},
               const Eigen::Vector3d& input_center_of_mass = Eigen::Vector3d::Zero());
  /// Adds body `name` as `spec` says (scene_body.hpp), from its body file: each file is read and its seal checked
  /// once per builder, however many bodies share it. Throws SceneError (key "file" for a file that cannot be read,
  /// and as make_body_model(name, spec, data) does), std::invalid_argument for a name already used.
  int add_body(const std::string& name, const SceneBody& spec, const Placement& placement = {});
  /// The index of body `name`; throws std::invalid_argument "no body 'name' in the scene".
  [[nodiscard]] int body(const std::string& name) const;

  /// A body file's interface of body `body` (the error names the interfaces there are).
  [[nodiscard]] Marker interface(const std::string& body, const std::string& name) const;
  /// A point fixed in the body, in its input frame [m] (the CAD coordinates the body file was made from). Throws
  /// std::invalid_argument for a body this builder did not add.
  [[nodiscard]] Marker point(const std::string& body, const Eigen::Vector3d& input_point) const;
  /// A node of its mesh (0-based): it follows the node's deformation.
  [[nodiscard]] Marker node(const std::string& body, Eigen::Index node) const;
  /// A fixed point in space [m].
  [[nodiscard]] static Marker ground(const Eigen::Vector3d& point) { return ground_marker(point); }

  /// Joins `first` to `second`, or to ground where `first` is at the start when `second` is empty, with the joint
  /// rows of `type` (joint.hpp). `axis` (global) is required for revolute, prismatic and driven-revolute joints and
  /// refused for the others; `drive` is required for a driven-revolute joint and refused for the others. Returns the
  /// joint's index in System::joints(). Throws std::invalid_argument naming the joint for those, a negative ramp, a
  /// marker on no body of the system, and as make_joint does (a zero axis, ...).
  std::size_t add_joint(const std::string& name, JointType type, const Marker& first,
                        const std::optional<Marker>& second = std::nullopt,
                        const std::optional<Eigen::Vector3d>& axis = std::nullopt,
                        const std::optional<JointDrive>& drive = std::nullopt);

  /// A force [N] (global axes) at a marker, times the shape's factor; or any function of time.
  void add_force(const Marker& at, const Eigen::Vector3d& force, const LoadShape& shape = {});
  void add_force(const Marker& at, std::function<Eigen::Vector3d(double)> force);
  /// A torque [N m] (global axes) at a marker, times the shape's factor; or any function of time.
  void add_torque(const Marker& at, const Eigen::Vector3d& torque, const LoadShape& shape = {});
  void add_torque(const Marker& at, std::function<Eigen::Vector3d(double)> torque);
  /// A linear spring-damper between two markers (system.hpp: SpringDamper): stiffness [N/m], damping [N s/m], rest
  /// length [m], by default the markers' initial distance (no preload). Throws std::invalid_argument as
  /// System::add_spring does.
  void add_spring(const std::string& name, const Marker& first, const Marker& second, double stiffness,
                  double damping = 0.0, const std::optional<double>& rest_length = std::nullopt);

  [[nodiscard]] System& system() { return system_; }
  [[nodiscard]] const System& system() const { return system_; }

 private:
  System& system_;
  std::vector<std::optional<Eigen::Vector3d>> input_center_of_mass_;  ///< by System index: set for this builder's bodies
  std::unordered_map<std::string, int> index_;                         ///< this builder's bodies by name
  std::map<std::string, std::shared_ptr<const format::BodyData>> files_;  ///< read by add_body, by canonical path
};

}  // namespace flexbody::runtime
