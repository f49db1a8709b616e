#include "flexbody/runtime/scene_builder.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

namespace flexbody::runtime {

std::function<double(double)> drive_angle(const JointDrive& drive) {
  return [speed = drive.speed, ramp = drive.ramp](double t) {
    if (ramp <= 0.0 || t >= ramp) return speed * (t - 0.5 * ramp);
    return 0.5 * speed * (t - ramp / std::numbers::pi * std::sin(std::numbers::pi * t / ramp));
  };
}

std::function<double(double)> drive_angle_rate(const JointDrive& drive) {
  return [speed = drive.speed, ramp = drive.ramp](double t) {
    if (ramp <= 0.0 || t >= ramp) return speed;
    return 0.5 * speed * (1.0 - std::cos(std::numbers::pi * t / ramp));
  };
}

int SceneBuilder::add_body(const std::string& name, BodyModel model, const Placement& placement,
                           const Eigen::Vector3d& input_center_of_mass) {
  BodyState state;
  state.orientation = placement.rotation;
  state.position = placement.position + placement.rotation * input_center_of_mass;  // the input frame's origin
  state.velocity = placement.velocity;
  state.angular_velocity = placement.angular_velocity;
  const int index = system_.add_body(name, std::move(model), state);
  if (static_cast<std::size_t>(index) >= input_center_of_mass_.size())
    input_center_of_mass_.resize(static_cast<std::size_t>(index) + 1, Eigen::Vector3d::Zero());
  input_center_of_mass_[static_cast<std::size_t>(index)] = input_center_of_mass;
  return index;
}

int SceneBuilder::body(const std::string& name) const {
  for (int b = 0; b < system_.body_count(); ++b)
    if (system_.body_name(b) == name) return b;
  throw std::invalid_argument("no body '" + name + "' in the scene");
}

Marker SceneBuilder::interface(const std::string& body_name, const std::string& name) const {
  const int b = body(body_name);
  return interface_marker(system_.model(b), b, body_name, name);
}

Marker SceneBuilder::point(const std::string& body_name, const Eigen::Vector3d& input_point) const {
  const int b = body(body_name);
  const Eigen::Vector3d com = static_cast<std::size_t>(b) < input_center_of_mass_.size()
                                  ? input_center_of_mass_[static_cast<std::size_t>(b)]
                                  : Eigen::Vector3d::Zero();
  return point_marker(system_.model(b), b, body_name, input_point - com);
}

Marker SceneBuilder::node(const std::string& body_name, Eigen::Index index) const {
  const int b = body(body_name);
  return node_marker(system_.model(b), b, body_name, index);
}

std::size_t SceneBuilder::add_joint(const std::string& name, JointType type, const Marker& first,
                                    const std::optional<Marker>& second, const Eigen::Vector3d& axis,
                                    const JointDrive& drive) {
  const Eigen::VectorXd q1 = system_.initial_body_coordinates(first.body);
  const Marker other = second ? *second : ground_marker(marker_position(first, q1));
  const Eigen::VectorXd q2 = system_.initial_body_coordinates(other.body);
  std::function<double(double)> angle, angle_rate;
  if (type == JointType::driven_revolute) {
    angle = drive_angle(drive);
    angle_rate = drive_angle_rate(drive);
  }
  system_.add_joint(make_joint(name, type, first, other, axis, q1, q2, std::move(angle), std::move(angle_rate)));
  return system_.joints().size() - 1;
}

}  // namespace flexbody::runtime
