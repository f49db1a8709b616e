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
  options.volume_tolerance = 0.05;  // the linear mesh misses 2 % of the volume here, on purpose (below)
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

// A .msh whose quadratic tetrahedron is folded by a mid-edge node (gmsh's node 5, the middle of edge (0,1), put on
// corner 2): its corners are a valid tetrahedron, so only the Jacobian at the Gauss points and nodes catches it, and
// the import refuses the file naming the element.
TEST(GmshOrder2, AFoldedQuadraticTetrahedronIsRefused) {
  const auto dir = flexbody::test::scratch_dir();
  std::ofstream(dir / "folded.msh") << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                                       "$Nodes\n1 10 1 10\n3 1 0 10\n1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n"
                                       "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                       "0 1 0\n0.5 0.5 0\n0 0.5 0\n0 0 0.5\n0 0.5 0.5\n0.5 0 0.5\n"
                                       "$EndNodes\n$Elements\n1 1 1 1\n3 1 11 1\n1 1 2 3 4 5 6 7 8 9 10\n"
                                       "$EndElements\n";
  fp::GmshImportOptions options;
  options.unit = fp::LengthUnit::metre;
  options.order = 2;
  try {
    (void)fp::import_tet_mesh(dir / "folded.msh", options);
    FAIL() << "a folded element was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("folded.msh: 1 of 1 quadratic tetrahedra are folded by their curved edges"),
              std::string::npos) << e.what();
  }
  // The same file with the node at its edge's middle is a valid straight element.
  std::ofstream(dir / "straight.msh") << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                                         "$Nodes\n1 10 1 10\n3 1 0 10\n1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n"
                                         "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                         "0.5 0 0\n0.5 0.5 0\n0 0.5 0\n0 0 0.5\n0 0.5 0.5\n0.5 0 0.5\n"
                                         "$EndNodes\n$Elements\n1 1 1 1\n3 1 11 1\n1 1 2 3 4 5 6 7 8 9 10\n"
                                         "$EndElements\n";
  const fp::ImportedMesh straight = fp::import_tet_mesh(dir / "straight.msh", options);
  ASSERT_TRUE(straight.quadratic.has_value());
  EXPECT_EQ(straight.quadratic->node_count(), 10);
  EXPECT_NEAR(fp::mesh_quality(*straight.quadratic).min_jacobian_ratio, 1.0, 1e-12);
}

// Without an order asked for, a .msh is read in the order it holds (the default element order is for meshes fbprep
// makes); one that holds both kinds of tetrahedra is refused with or without an order: either reading would drop
// volumes.
TEST(GmshOrder2, AMshIsReadInTheOrderItHolds) {
  const auto dir = flexbody::test::scratch_dir();
  const std::string nodes = "$Nodes\n1 10 1 10\n3 1 0 10\n1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n"
                            "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                            "0.5 0 0\n0.5 0.5 0\n0 0.5 0\n0 0 0.5\n0 0.5 0.5\n0.5 0 0.5\n$EndNodes\n";
  std::ofstream(dir / "linear.msh") << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n" << nodes
                                    << "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";
  std::ofstream(dir / "quadratic.msh") << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n" << nodes
                                       << "$Elements\n1 1 1 1\n3 1 11 1\n1 1 2 3 4 5 6 7 8 9 10\n$EndElements\n";
  // Two volumes, one of each kind (as gmsh writes them, a block per volume; gmsh 4.8 cannot read both kinds in one
  // volume: its getElementsByType then writes past its own allocation, valgrind).
  std::ofstream(dir / "mixed.msh") << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                                      "$Nodes\n2 14 1 14\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                      "3 2 0 10\n5\n6\n7\n8\n9\n10\n11\n12\n13\n14\n2 0 0\n3 0 0\n2 1 0\n2 0 1\n"
                                      "2.5 0 0\n2.5 0.5 0\n2 0.5 0\n2 0 0.5\n2 0.5 0.5\n2.5 0 0.5\n$EndNodes\n"
                                      "$Elements\n2 2 1 2\n3 1 4 1\n1 1 2 3 4\n3 2 11 1\n2 5 6 7 8 9 10 11 12 13 14\n"
                                      "$EndElements\n";
  fp::GmshImportOptions options;  // no order
  options.unit = fp::LengthUnit::metre;
  const fp::ImportedMesh linear = fp::import_tet_mesh(dir / "linear.msh", options);
  EXPECT_FALSE(linear.quadratic.has_value());
  EXPECT_EQ(linear.mesh.tets.rows(), 1);
  const fp::ImportedMesh quadratic = fp::import_tet_mesh(dir / "quadratic.msh", options);
  ASSERT_TRUE(quadratic.quadratic.has_value());
  EXPECT_EQ(quadratic.quadratic->node_count(), 10);
  for (const std::optional<int> order : {std::optional<int>(), std::optional<int>(1), std::optional<int>(2)}) {
    options.order = order;
    try {
      (void)fp::import_tet_mesh(dir / "mixed.msh", options);
      FAIL() << "a mesh of both orders was read, order " << order.value_or(0);
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("mixed.msh: the mesh holds both linear and quadratic tetrahedra; fbprep "
                                           "reads one kind"), std::string::npos) << e.what();
    }
  }
}
