#include "test_bodies.hpp"

#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/gcms_constants.hpp"
#include "flexbody/preprocess/mass_properties.hpp"

namespace flexbody::test {

format::BodyData free_free_body(const AssembledMesh& mesh, const preprocess::Material& material, int modes) {
  format::BodyData b;
  b.mass = preprocess::mass_properties(mesh.scalar_mass, mesh.mesh.nodes);
  b.mesh.nodes = mesh.mesh.nodes.rowwise() - b.mass.center_of_mass_input.transpose();
  b.mesh.tets = mesh.mesh.tets;
  preprocess::FreeFreeOptions options;
  options.modes = modes;
  const preprocess::FreeFreeModes m =
      preprocess::free_free_modes(b.mesh.nodes, mesh.stiffness, mesh.scalar_mass, material, options);
  b.modes.frequencies_hz = m.frequencies_hz;
  b.modes.relative_residuals = m.relative_residuals;
  b.modes.upsilon = preprocess::upsilon_from_modes(m.vectors);
  b.gcms = preprocess::gcms_constants(mesh.stiffness, mesh.scalar_mass, b.mesh.nodes, b.modes.upsilon);
  return b;
}

format::BodyData soft_bar(double length, int cells, int modes) {
  const preprocess::Material soft{"soft", 5e9, 0.3, 1000.0};
  return free_free_body(assemble(box_mesh(length, 0.04, 0.02, cells, 2, 1), soft), soft, modes);
}

}  // namespace flexbody::test
