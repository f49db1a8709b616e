// Inputs with faces and no volume (issue 28 item 3): sewn into a solid when they close one, refused naming the free
// edges when they do not. The shells are written by gmsh itself: the faces of a 10 x 5 x 2 mm box as a STEP file
// without the box's solid, all six of them or five.
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/mesh_topology.hpp"
#include "test_meshes.hpp"

#include <gmsh.h>
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <string>

namespace fp = flexbody::preprocess;

namespace {

std::filesystem::path box_faces(const std::string& name, bool all_six) {
  const auto path = flexbody::test::scratch_dir() / name;
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("shell");
  const int box = gmsh::model::occ::addBox(0, 0, 0, 10, 5, 2);
  gmsh::model::occ::synchronize();
  gmsh::vectorpair faces;
  gmsh::model::getBoundary({{3, box}}, faces, false, false, false);
  gmsh::model::occ::remove({{3, box}});  // the solid goes, its faces stay
  if (!all_six) gmsh::model::occ::remove({faces.front()});
  gmsh::model::occ::synchronize();
  gmsh::write(path.string());
  gmsh::finalize();
  return path;
}

}  // namespace

// Six faces close the box: sewn into one solid, whose CAD volume is the box's 100 mm³ (OpenCASCADE's, to 1e-12) and
// which the mesh holds to the default 0.5 % (a box: exactly, to rounding).
TEST(ShellSewing, AClosedShellIsSewnIntoASolid) {
  const fp::ImportedMesh mesh = fp::import_tet_mesh(box_faces("closed_shell.step", true), {});
  EXPECT_EQ(mesh.sewn_faces, 6);
  EXPECT_EQ(mesh.volumes, 1);
  ASSERT_TRUE(mesh.cad_volume_m3.has_value());
  EXPECT_NEAR(*mesh.cad_volume_m3 / 1e-7, 1.0, 1e-12);
  EXPECT_NEAR(fp::mesh_quality(mesh.mesh).volume_m3 / 1e-7, 1.0, 1e-12);
}

// Five faces leave the box open along the missing face's four edges: refused in one line that counts them.
TEST(ShellSewing, AnOpenShellIsRefusedNamingItsFreeEdges) {
  try {
    (void)fp::import_tet_mesh(box_faces("open_shell.step", false), {});
    FAIL() << "an open shell was taken";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos);
    EXPECT_NE(what.find("open_shell.step: the input has no volume (5 surfaces), and sewing them made no closed solid: 4 "
                        "free edges (each bounds one face only) leave 1 shell(s) open"), std::string::npos) << what;
  }
}

// A face beside a solid (a 10 x 5 x 2 mm box and, 20 mm away, a 3 x 3 mm rectangle, in one STEP file) bounds nothing:
// the part is meshed without it (the box's volume, to rounding), and the import counts it instead of losing it
// silently. Its curves and points bound the face, so they are not loose themselves.
TEST(ShellSewing, AFaceBesideTheSolidIsLeftOutAndCounted) {
  const auto path = flexbody::test::scratch_dir() / "box_and_face.step";
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("loose");
  gmsh::model::occ::addBox(0, 0, 0, 10, 5, 2);
  gmsh::model::occ::addRectangle(30, 0, 0, 3, 3);
  gmsh::model::occ::synchronize();
  gmsh::write(path.string());
  gmsh::finalize();
  const fp::ImportedMesh mesh = fp::import_tet_mesh(path, {});
  EXPECT_EQ(mesh.loose_entities, (std::array<int, 3>{0, 0, 1}));
  EXPECT_EQ(mesh.sewn_faces, 0);
  EXPECT_NEAR(fp::mesh_quality(mesh.mesh).volume_m3 / 1e-7, 1.0, 1e-12);
}
