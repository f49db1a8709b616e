// A scene's finish (scene.hpp: finish_scene), whichever way it was built: from a scene file or in code.
#include "flexbody/scene/scene.hpp"

#include "flexbody/runtime/joint.hpp"

#include <algorithm>
#include <cmath>

namespace flexbody::scene {
namespace {

// Rows that repeat earlier ones would make the DAE singular: they are left out, as Adams does, and the summary says
// which (a planar four-bar of revolute joints repeats three).
void remove_redundant(Scene& scene, const Eigen::VectorXd& q) {
  for (runtime::RemovedConstraint& c : scene.system.remove_redundant_constraints(0.0, q))
    scene.removed.push_back(std::move(c));
}

}  // namespace

void finish_scene(Scene& scene, const runtime::InitialAssemblyOptions& assembly) {
  runtime::System& system = scene.system;
  // Found before the assembly, whose Newton matrix they would make singular too, and again after it (rows dependent
  // only once the gaps are closed).
  remove_redundant(scene, system.initial_coordinates());

  const bool applied_loads = !system.forces().empty() || !system.torques().empty();
  bool damped_springs = false, springs_to_ground = false, damped_bodies = false, driven = false, joints_to_ground = false;
  for (const runtime::SpringDamper& s : system.springs()) {
    damped_springs = damped_springs || s.damping != 0.0;
    springs_to_ground = springs_to_ground || s.first.body == runtime::kGround || s.second.body == runtime::kGround;
  }
  for (int b = 0; b < system.body_count(); ++b) damped_bodies = damped_bodies || system.model(b).damping.size() > 0;
  for (const runtime::Joint& j : system.joints()) {
    driven = driven || j.type == runtime::JointType::driven_revolute;
    joints_to_ground = joints_to_ground || j.first.body == runtime::kGround || j.second.body == runtime::kGround;
  }
  scene.conserves.energy = !applied_loads && !damped_springs && !damped_bodies && !driven;
  scene.conserves.angular_momentum = scene.conserves.energy && !joints_to_ground && !springs_to_ground;

  // Close the joints' gaps (an interface's point comes from a mesh, micrometres off the CAD's nominal position) by
  // the least mass-weighted move of the bodies (runtime/initial_assembly.hpp).
  scene.assembly = runtime::initial_assembly(system, assembly);
  if (scene.assembly.iterations > 0) {
    const Eigen::VectorXd q = system.initial_coordinates();
    for (runtime::RemovedConstraint& c : scene.removed) {  // the rows removed before: their gaps once assembled
      const runtime::Joint& j = system.joints()[c.joint];
      c.gap = std::abs(runtime::joint_type_residuals(j, 0.0, system.body_coordinates(q, j.first.body),
                                                     system.body_coordinates(q, j.second.body))(c.row));
    }
    remove_redundant(scene, q);
  }
}

}  // namespace flexbody::scene
