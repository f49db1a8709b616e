// gmsh's second-order tetrahedra (issue 15): mid-edge nodes of boundary edges on the CAD surface, so a curved part is
// bounded by curved faces. A cylinder r = 0.05 m, 0.2 m long, meshed at h = 0.02 m (a coarse mesh, 2.5 elements across
// the radius).
#include "flexbody/format/tet10_element.hpp"
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/mesh_topology.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"
#include "test_meshes.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <string>

namespace fp = flexbody::preprocess;

namespace {

constexpr double kRadius = 0.05, kLength = 0.2, kSize = 0.02;

fp::ImportedMesh cylinder(int order) {
  const auto dir = flexbody::test::scratch_dir();
  std::ofstream(dir / "cylinder.geo") << "SetFactory(\"OpenCASCADE\");\nCylinder(1) = {0, 0, 0, 0, 0, " << kLength
                                      << ", " << kRadius << "};\n";
  fp::GmshImportOptions options;
  options.unit = fp::LengthUnit::metre;
  options.mesh_size = kSize;
  options.order = order;
  return fp::import_tet_mesh(dir / "cylinder.geo", options);
}

}  // namespace

// The quadratic mesh's corners are the linear mesh's nodes; every mid-edge node on the lateral surface lies on the
// cylinder (to gmsh's geometric tolerance), where a straight edge's middle would lie inside it by up to
// r (1 − cos(h/2r)) ≈ 1 mm here; and the curved mesh's volume (the mass of ρ = 1) is within 5e-5 of πr²L, where the
// linear mesh lacks its chords' segments (measured: 2.0e-2 linear, 3.1e-5 quadratic; mid-edge nodes 7e-18 m off).
TEST(GmshOrder2, MidEdgeNodesLieOnTheCurvedSurface) {
  const fp::ImportedMesh linear = cylinder(1);
  const fp::ImportedMesh quadratic = cylinder(2);
  EXPECT_FALSE(linear.quadratic.has_value());
  ASSERT_TRUE(quadratic.quadratic.has_value());
  const fp::Tet10Mesh& q = *quadratic.quadratic;
  ASSERT_EQ(q.nodes.topRows(quadratic.mesh.node_count()), quadratic.mesh.nodes);
  for (Eigen::Index e = 0; e < q.element_count(); ++e)
    for (int a = 0; a < 4; ++a) ASSERT_EQ(q.tets(e, a), quadratic.mesh.tets(e, a));
  int on_surface = 0;
  double worst = 0.0;
  for (Eigen::Index e = 0; e < q.element_count(); ++e)
    for (int k = 0; k < 6; ++k) {
      const auto [i, j] = flexbody::format::kTet10Edges[static_cast<std::size_t>(k)];
      const Eigen::RowVector3d p = q.nodes.row(q.tets(e, i)), r = q.nodes.row(q.tets(e, j)), m = q.nodes.row(q.tets(e, 4 + k));
      const bool lateral = std::abs(std::hypot(p.x(), p.y()) - kRadius) < 1e-9 && std::abs(std::hypot(r.x(), r.y()) - kRadius) < 1e-9 &&
                           std::abs(p.z() - r.z()) < 0.5 * kSize;  // both ends on the mantle: a boundary edge there
      if (!lateral || (p - r).head<2>().norm() < 1e-3 * kRadius) continue;  // skip axial edges along the mantle
      ++on_surface;
      worst = std::max(worst, std::abs(std::hypot(m.x(), m.y()) - kRadius));
    }
  const double linear_volume = fp::mesh_quality(linear.mesh).volume_m3;
  const fp::SparseMatrix m_s = fp::assemble_tet10(q, {"unit", 1e9, 0.3, 1.0}).scalar_mass;  // upper triangle, ρ = 1
  const double quadratic_volume = 2.0 * m_s.sum() - m_s.diagonal().sum();
  const double exact = std::numbers::pi * kRadius * kRadius * kLength;
  std::printf("%d mantle edges, their middles off the radius by at most %.3g m; volume error linear %.3g, quadratic "
              "%.3g\n", on_surface, worst, 1.0 - linear_volume / exact, 1.0 - quadratic_volume / exact);
  EXPECT_GT(on_surface, 20);
  EXPECT_LT(worst, 1e-9 * kRadius);
  EXPECT_LT(std::abs(1.0 - quadratic_volume / exact), 5e-5);
  EXPECT_GT(1.0 - linear_volume / exact, 1e-2);
}

// The import takes orders 1 and 2 only.
TEST(GmshOrder2, OtherOrdersAreRefused) {
  try {
    (void)cylinder(3);
    FAIL() << "order 3 was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("element order 3: the element order is 1"), std::string::npos) << e.what();
  }
}

// gmsh sets OpenMP's thread count to its General.NumThreads (1) when it starts; the import gives the process its own
// count back, or fbprep's assembly, stress recovery and Eigen's products after meshing ran on one thread (measured
// before the fix: the quadratic bracket's assembly at 81k DOFs took 0.42 s with OMP_NUM_THREADS=2, 0.25 s after).
TEST(GmshOrder2, TheImportLeavesOpenMpItsThreadCount) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(3);
  (void)cylinder(1);
  EXPECT_EQ(omp_get_max_threads(), 3);
  omp_set_num_threads(before);
}
