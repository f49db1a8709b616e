// The mesh against the CAD solid's volume (issue 28 item 2): the default size is refined until the mesh holds it, a
// size the user gave that misses it is refused with one that would do. A cylinder of radius 0.05 m (OpenCASCADE
// .geo): linear tetrahedra cut its mantle along chords, so the meshed volume falls short by about (2π/n)²/6 for n
// elements around (2 % at 0.02 m).
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/mesh_topology.hpp"
#include "test_meshes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <string>

namespace fp = flexbody::preprocess;

namespace {

constexpr double kRadius = 0.05;

fp::ImportedMesh cylinder(double length, double size, int order = 1, double tolerance = 5e-3,
                          double search_elements = 2e6) {
  const auto dir = flexbody::test::scratch_dir();
  std::ofstream(dir / "volume_cylinder.geo") << "SetFactory(\"OpenCASCADE\");\nCylinder(1) = {0, 0, 0, 0, 0, "
                                             << length << ", " << kRadius << "};\n";
  fp::GmshImportOptions options;
  options.unit = fp::LengthUnit::metre;
  options.mesh_size = size;
  options.order = order;
  options.volume_tolerance = tolerance;
  options.volume_search_elements = search_elements;
  return fp::import_tet_mesh(dir / "volume_cylinder.geo", options);
}

}  // namespace

// The CAD volume is OpenCASCADE's, πr²L to its own accuracy (1e-9 asserted; measured 1e-15). A slender cylinder, 1 m
// long: the default size (diagonal / 25 = 40 mm, 8 elements around) misses 7.9 % with linear elements. It is
// halved until the mesh holds the volume to 0.5 % (measured: twice, to 10 mm, where it misses 0.498 %); the first mesh's error and the size
// it started from are kept for the report.
TEST(MeshVolume, TheDefaultSizeIsRefinedUntilTheMeshHoldsTheCadVolume) {
  constexpr double kLength = 1.0;
  const double volume = std::numbers::pi * kRadius * kRadius * kLength;
  const fp::ImportedMesh mesh = cylinder(kLength, 0.0);
  ASSERT_TRUE(mesh.cad_volume_m3.has_value());
  EXPECT_NEAR(*mesh.cad_volume_m3 / volume, 1.0, 1e-9);
  const double diagonal = std::sqrt(2 * std::pow(2 * kRadius, 2) + kLength * kLength);
  ASSERT_TRUE(mesh.first_volume_error.has_value());
  EXPECT_LT(*mesh.first_volume_error, -0.05);
  EXPECT_NEAR(mesh.refined_from_m / (diagonal / 25.0), 1.0, 1e-5);  // gmsh pads its bounding box by 1e-7 m a side
  EXPECT_NEAR(mesh.mesh_size_m / mesh.refined_from_m, 0.25, 1e-15);
  std::printf("first mesh %.3g, refined %.3g of the volume\n", *mesh.first_volume_error,
              fp::mesh_quality(mesh.mesh).volume_m3 / volume - 1.0);
  EXPECT_LT(std::abs(fp::mesh_quality(mesh.mesh).volume_m3 / volume - 1.0), 5e-3);
}

// Quadratic elements follow the mantle: the default size holds the volume at once (0.2 m long; measured 3e-5), with
// no refinement.
TEST(MeshVolume, QuadraticElementsHoldTheVolumeAtTheDefaultSize) {
  const fp::ImportedMesh mesh = cylinder(0.2, 0.0, 2);
  ASSERT_TRUE(mesh.first_volume_error.has_value());
  EXPECT_LT(std::abs(*mesh.first_volume_error), 1e-3);
  EXPECT_EQ(mesh.refined_from_m, 0.0);
}

// The user's 0.02 m on the 0.2 m cylinder misses 2 %: refused in one line with the error, the tolerance, a size that
// holds it (0.01 m: -0.48 %) and the flag that accepts this mesh; with that tolerance the same size is taken.
TEST(MeshVolume, AUserSizeThatMissesTheVolumeIsRefusedWithOneThatHoldsIt) {
  try {
    (void)cylinder(0.2, 0.02);
    FAIL() << "a mesh missing 2 % of the volume was taken";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos);
    EXPECT_NE(what.find("volume_cylinder.geo: the mesh at --mesh-size 0.02 m holds 98."), std::string::npos) << what;
    EXPECT_NE(what.find("beyond the 0.5 % tolerance; --mesh-size 0.01 m holds it"), std::string::npos) << what;
    EXPECT_NE(what.find("--volume-tolerance"), std::string::npos) << what;
  }
  const fp::ImportedMesh taken = cylinder(0.2, 0.02, 1, 0.03);
  EXPECT_NEAR(taken.mesh_size_m, 0.02, 1e-15);
  EXPECT_EQ(taken.refined_from_m, 0.0);
}

// The search for a size that would hold the volume stops before a mesh beyond GmshImportOptions::volume_search_elements
// (2e6 tetrahedra by default, about 1e6 linear DOFs: no search costs more than a run). With the bound at 100 the
// 0.2 m cylinder's first halving is not tried, and the refusal says why and what else to do.
TEST(MeshVolume, TheSearchStopsAtItsElementBoundAndSaysSo) {
  try {
    (void)cylinder(0.2, 0.02, 1, 5e-3, 100.0);
    FAIL() << "a mesh missing 2 % of the volume was taken";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos);
    EXPECT_NE(what.find("the mesh at --mesh-size 0.02 m holds 98."), std::string::npos) << what;
    EXPECT_NE(what.find("a finer mesh would pass 1e+02 tetrahedra, so none was tried: --order 2 follows curved faces"),
              std::string::npos) << what;
    EXPECT_NE(what.find("(or --volume-tolerance 0.021 accepts this mesh)"), std::string::npos) << what;
  }
}

// GmshImportOptions::thin_feature_elements: a block 40 x 40 x 10 mm with a fin 1 mm thick and 10 mm tall on top.
// The default size (diagonal / 25 = 2.4 mm) leaves the fin about one element thick (measured: 27 nodes strictly
// inside its thickness); with 2 across, the fin's corners (whose shortest curves are its 1 mm edges) ask for 0.5 mm,
// which the floor of kThinFeatureFloor = 1/4 of the size raises to 0.6 mm, and gmsh fills the fin (94 nodes; 126
// without the floor), while the block away from it keeps the default size (6991 -> 8812 tetrahedra).
TEST(MeshVolume, ThinFeaturesGetElementsAcrossThem) {
  const auto dir = flexbody::test::scratch_dir();
  std::ofstream(dir / "fin.geo") << "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 0.04, 0.04, 0.01};\n"
                                    "Box(2) = {0, 0.0195, 0.01, 0.04, 0.001, 0.01};\n"
                                    "BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; }\n";
  auto inside_fin = [](const fp::ImportedMesh& mesh) {
    int count = 0;
    for (Eigen::Index i = 0; i < mesh.mesh.nodes.rows(); ++i) {
      const double y = mesh.mesh.nodes(i, 1), z = mesh.mesh.nodes(i, 2);
      if (z > 0.0105 && y > 0.0197 && y < 0.0203) ++count;
    }
    return count;
  };
  fp::GmshImportOptions options;
  options.unit = fp::LengthUnit::metre;
  options.order = 1;
  const fp::ImportedMesh plain = fp::import_tet_mesh(dir / "fin.geo", options);
  options.thin_feature_elements = 2.0;
  const fp::ImportedMesh thin = fp::import_tet_mesh(dir / "fin.geo", options);
  std::printf("fin: %d and %d nodes inside its thickness; %ld and %ld tetrahedra\n", inside_fin(plain), inside_fin(thin),
              static_cast<long>(plain.mesh.element_count()), static_cast<long>(thin.mesh.element_count()));
  EXPECT_GT(inside_fin(thin), 3 * inside_fin(plain));
  EXPECT_GT(thin.mesh.element_count(), plain.mesh.element_count());
  EXPECT_LT(thin.mesh.element_count(), 3 * plain.mesh.element_count());
  EXPECT_NEAR(thin.mesh_size_m, plain.mesh_size_m, 1e-12);  // the uniform size is unchanged; only the points'

  // In gmsh's built-in kernel (no OpenCASCADE lengths) the curves are measured by their chords: a plate 40 x 1 x 10 mm
  // extruded from a rectangle.
  std::ofstream(dir / "plate.geo") << "Point(1) = {0, 0, 0};\nPoint(2) = {0.04, 0, 0};\nPoint(3) = {0.04, 0.001, 0};\n"
                                      "Point(4) = {0, 0.001, 0};\nLine(1) = {1, 2};\nLine(2) = {2, 3};\nLine(3) = {3, 4};\n"
                                      "Line(4) = {4, 1};\nCurve Loop(1) = {1, 2, 3, 4};\nPlane Surface(1) = {1};\n"
                                      "Extrude {0, 0, 0.01} { Surface{1}; }\n";
  options.thin_feature_elements = 0.0;
  const fp::ImportedMesh built_in = fp::import_tet_mesh(dir / "plate.geo", options);
  options.thin_feature_elements = 2.0;
  EXPECT_GT(fp::import_tet_mesh(dir / "plate.geo", options).mesh.element_count(), 2 * built_in.mesh.element_count());
  // A .msh is used as it is: thin features there are refused, not ignored.
  std::ofstream(dir / "one.msh") << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n"
                                    "0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n"
                                    "$EndElements\n";
  try {
    (void)fp::import_tet_mesh(dir / "one.msh", options);
    FAIL() << "--thin-features on a .msh was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("one.msh: --thin-features sizes a mesh fbprep makes"), std::string::npos) << e.what();
  }
}
