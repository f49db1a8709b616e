// Consistent mass: mass, centre of mass and inertia of a box exactly, of a cylinder within the mesh's
// geometric error.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "flexbody/preprocess/mesh_topology.hpp"
#include "test_meshes.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <numbers>

namespace fp = flexbody::preprocess;

namespace {

flexbody::format::MassProperties consistent_mass_properties(const fp::TetMesh& mesh, double density) {
  const auto graph = fp::NodeGraph::build(mesh);
  const auto mass = fp::assemble_scalar_mass(mesh, graph, fp::element_geometries(mesh), density, fp::MassScheme::consistent);
  return fp::mass_properties(mass, mesh.nodes);
}

}  // namespace

TEST(MassProperties, BoxIsExact) {
  // A box offset from the origin: the centre of mass and the parallel-axis shift must both be right.
  const double lx = 0.3, ly = 0.2, lz = 0.1, rho = 7850.0;
  fp::TetMesh mesh = flexbody::test::box_mesh(lx, ly, lz, 3, 4, 2);
  mesh.nodes.rowwise() += Eigen::RowVector3d(1.0, -2.0, 0.5);
  const auto props = consistent_mass_properties(mesh, rho);
  const double m = rho * lx * ly * lz;
  // The consistent mass integrates the (piecewise linear) fields exactly: only round-off remains.
  EXPECT_NEAR(props.mass, m, 1e-13 * m);
  EXPECT_LT((props.center_of_mass_input - Eigen::Vector3d(1.15, -1.9, 0.55)).norm(), 1e-14);
  const Eigen::Vector3d expected = m / 12.0 * Eigen::Vector3d(ly * ly + lz * lz, lx * lx + lz * lz, lx * lx + ly * ly);
  EXPECT_LT((props.inertia_about_com - Eigen::Matrix3d(expected.asDiagonal())).norm(), 1e-13 * expected.norm());
}

TEST(MassProperties, CylinderWithinGeometricError) {
  // A cylinder of radius r along z, meshed by gmsh: the mesh is a polyhedron inscribed in it. With
  // chords of length h the cross-section lacks a fraction 1 - sin(t)/t ~ t^2/6 of its area, t = h/r;
  // allow twice that for gmsh's uneven chords (and twice again for the r^4 terms of the inertia).
  const double r = 0.05, length = 0.2, rho = 2700.0, h = 0.01;
  const auto dir = flexbody::test::scratch_dir();
  std::ofstream(dir / "cylinder.geo") << "SetFactory(\"OpenCASCADE\");\nCylinder(1) = {0, 0, 0, 0, 0, " << length
                                      << ", " << r << "};\n";
  fp::GmshImportOptions options;
  options.unit = fp::LengthUnit::metre;
  options.mesh_size = h;
  options.order = 1;  // the chords of linear tetrahedra (the deficit below)
  const fp::ImportedMesh imported = fp::import_tet_mesh(dir / "cylinder.geo", options);
  const auto props = consistent_mass_properties(imported.mesh, rho);

  // Exact for the mesh itself: mass = rho x meshed volume.
  EXPECT_NEAR(props.mass, rho * fp::mesh_quality(imported.mesh).volume_m3, 1e-12 * props.mass);
  const double t = h / r, deficit = t * t / 3.0;
  const double m = rho * std::numbers::pi * r * r * length;
  EXPECT_LT(props.mass, m);
  EXPECT_NEAR(props.mass, m, deficit * m);
  EXPECT_LT((props.center_of_mass_input - Eigen::Vector3d(0, 0, length / 2)).norm(), 1e-3 * r);
  const double axial = m * r * r / 2.0, transverse = m * (3 * r * r + length * length) / 12.0;
  EXPECT_NEAR(props.inertia_about_com(2, 2), axial, 2 * deficit * axial);
  EXPECT_NEAR(props.inertia_about_com(0, 0), transverse, 2 * deficit * transverse);
  EXPECT_NEAR(props.inertia_about_com(1, 1), transverse, 2 * deficit * transverse);
  EXPECT_LT(std::abs(props.inertia_about_com(0, 1)), 1e-3 * transverse);
}
