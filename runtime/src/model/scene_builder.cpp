#include "flexbody/runtime/scene_builder.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
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

std::function<double(double)> load_factor(const LoadShape& shape) {
  return [ramp = shape.ramp, frequency = shape.frequency](double t) {
    const double rise = ramp > 0.0 ? std::min(1.0, t / ramp) : 1.0;
    return frequency > 0.0 ? rise * std::sin(2.0 * std::numbers::pi * frequency * t) : rise;
  };
}

int SceneBuilder::add_body(const std::string& name, BodyModel model, const Placement& placement,
                           const Eigen::Vector3d& input_center_of_mass) {
  BodyState state;
  state.orientation = placement.rotation;
  state.position = placement.position + placement.rotation * input_center_of_mass;  // the centre of mass's place
  state.velocity = placement.velocity;
  state.angular_velocity = placement.angular_velocity;
  const int index = system_.add_body(name, std::move(model), state);
  const auto k = static_cast<std::size_t>(index);
  if (k >= input_center_of_mass_.size()) input_center_of_mass_.resize(k + 1);
  input_center_of_mass_[k] = input_center_of_mass;
  index_[name] = index;
  return index;
}

int SceneBuilder::add_body(const std::string& name, const SceneBody& spec, const Placement& placement) {
  if (index_.count(name)) throw std::invalid_argument("body '" + name + "' is defined twice");
  // Each file is read (and its seal checked) once: a chain of 1024 copies of one part would otherwise spend 60 ms
  // per copy of the bracket on its SHA-256.
  const std::string key = std::filesystem::weakly_canonical(spec.file).string();
  auto found = files_.find(key);
  if (found == files_.end()) {
    try {
      found = files_.emplace(key, std::make_shared<const format::BodyData>(format::read_body_file(spec.file))).first;
    } catch (const std::exception& e) {
      throw SceneError("file", e.what());
    }
  }
  const format::BodyData& data = *found->second;
  return add_body(name, make_body_model(name, spec, data), placement, data.mass.center_of_mass_input);
}

int SceneBuilder::body(const std::string& name) const {
  if (const auto found = index_.find(name); found != index_.end()) return found->second;
  for (int b = 0; b < system_.body_count(); ++b)  // one added to the system directly
    if (system_.body_name(b) == name) return b;
  throw std::invalid_argument("no body '" + name + "' in the scene");
}

Marker SceneBuilder::interface(const std::string& body_name, const std::string& name) const {
  const int b = body(body_name);
  return interface_marker(system_.model(b), b, body_name, name);
}

Marker SceneBuilder::point(const std::string& body_name, const Eigen::Vector3d& input_point) const {
  const int b = body(body_name);
  const auto k = static_cast<std::size_t>(b);
  if (k >= input_center_of_mass_.size() || !input_center_of_mass_[k])
    throw std::invalid_argument("body '" + body_name + "' was added to the system directly, so its input frame is "
                                "unknown here: use a point marker about its centre of mass (point_marker)");
  return point_marker(system_.model(b), b, body_name, input_point - *input_center_of_mass_[k]);
}

Marker SceneBuilder::node(const std::string& body_name, Eigen::Index index) const {
  const int b = body(body_name);
  return node_marker(system_.model(b), b, body_name, index);
}

std::size_t SceneBuilder::add_joint(const std::string& name, JointType type, const Marker& first,
                                    const std::optional<Marker>& second, const std::optional<Eigen::Vector3d>& axis,
                                    const std::optional<JointDrive>& drive) {
  const std::string where = "joint '" + name + "': ";
  const bool has_axis = type == JointType::revolute || type == JointType::prismatic || type == JointType::driven_revolute;
  if (has_axis && !axis) throw std::invalid_argument(where + "a revolute, prismatic or driven-revolute joint needs an axis");
  if (!has_axis && axis) throw std::invalid_argument(where + "a spherical or fixed joint has no axis");
  const bool driven = type == JointType::driven_revolute;
  if (driven && !drive) throw std::invalid_argument(where + "a driven-revolute joint needs a drive (speed and ramp)");
  if (!driven && drive) throw std::invalid_argument(where + "only a driven-revolute joint has a drive");
  if (drive && !(std::isfinite(drive->speed) && drive->ramp >= 0.0 && std::isfinite(drive->ramp)))
    throw std::invalid_argument(where + "the drive's speed must be finite and its ramp >= 0");
  for (const Marker* m : {&first, second ? &*second : nullptr})
    if (m && m->body != kGround && !(m->body >= 0 && m->body < system_.body_count()))
      throw std::invalid_argument(where + "marker " + m->name + " is on no body of this system");
  const Eigen::VectorXd q1 = system_.initial_body_coordinates(first.body);
  const Marker other = second ? *second : ground_marker(marker_position(first, q1));
  const Eigen::VectorXd q2 = system_.initial_body_coordinates(other.body);
  std::function<double(double)> angle, angle_rate;
  if (drive) {
    angle = drive_angle(*drive);
    angle_rate = drive_angle_rate(*drive);
  }
  system_.add_joint(make_joint(name, type, first, other, axis.value_or(Eigen::Vector3d::UnitZ()), q1, q2,
                               std::move(angle), std::move(angle_rate)));
  return system_.joints().size() - 1;
}

void SceneBuilder::add_force(const Marker& at, const Eigen::Vector3d& force, const LoadShape& shape) {
  add_force(at, [force, factor = load_factor(shape)](double t) { return Eigen::Vector3d(factor(t) * force); });
}

void SceneBuilder::add_force(const Marker& at, std::function<Eigen::Vector3d(double)> force) {
  system_.add_force({at, std::move(force)});
}

void SceneBuilder::add_torque(const Marker& at, const Eigen::Vector3d& torque, const LoadShape& shape) {
  add_torque(at, [torque, factor = load_factor(shape)](double t) { return Eigen::Vector3d(factor(t) * torque); });
}

void SceneBuilder::add_torque(const Marker& at, std::function<Eigen::Vector3d(double)> torque) {
  system_.add_torque({at, std::move(torque)});
}

void SceneBuilder::add_spring(const std::string& name, const Marker& first, const Marker& second, double stiffness,
                              double damping, const std::optional<double>& rest_length) {
  SpringDamper spring;
  spring.name = name;
  spring.first = first;
  spring.second = second;
  spring.stiffness = stiffness;
  spring.damping = damping;
  spring.rest_length = rest_length ? *rest_length
                                   : (marker_position(second, system_.initial_body_coordinates(second.body)) -
                                      marker_position(first, system_.initial_body_coordinates(first.body))).norm();
  system_.add_spring(std::move(spring));
}

}  // namespace flexbody::runtime
