// fbprep with quadratic tetrahedra (issue 15) end to end, on the slender steel beam 1 x 0.05 x 0.05 m meshed by gmsh at
// 0.05 m: one element through the thickness, where linear tetrahedra lock (validation/README.md: Timoshenko's first
// free-free bending pair 263.46 Hz, cantilever 41.694 Hz).
#include "flexbody/format/body_file.hpp"
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/fbprep_pipeline.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"
#include "flexbody/preprocess/static_correction.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"
#include "cli_run.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <filesystem>
#include <string>
#include <vector>

namespace fp = flexbody::preprocess;

namespace {

constexpr double kFreeFree = 263.46, kCantilever = 41.694;  // Hz, Timoshenko

fp::PrepOptions beam(int order, const std::filesystem::path& dir, const std::string& name) {
  fp::PrepOptions options;
  options.input = flexbody::test::data_dir() / "gmsh-beam" / "beam_1m.geo";
  options.output = dir / name;
  options.mesh.unit = fp::LengthUnit::metre;
  options.mesh.mesh_size = 0.05;
  options.mesh.order = order;
  options.modes.modes = 4;
  return options;
}

fp::PlaneSelector end_face(double x) {
  fp::PlaneSelector plane;
  plane.point = Eigen::Vector3d(x, 0.0, 0.0);
  plane.normal = Eigen::Vector3d::UnitX();
  return plane;
}

double pair_error(const Eigen::VectorXd& frequencies, double reference) {
  return 0.5 * (frequencies(0) + frequencies(1)) / reference - 1.0;
}

}  // namespace

// Free-free, with an rbe3 interface on the tip face. Measured: quadratic 2 649 DOFs +0.063 %, linear 498 DOFs +66 %.
// Asserted: quadratic within 0.2 % (the 3D beam's own difference from Timoshenko is about 0.01 %, README), linear
// above 30 %. The interface holds every node of the face, mid-edge nodes included, with tributary-area weights
// whose centroid is the face's centre to rounding (1e-12 m); the default output region holds every node, and the
// body file reads back as order 2 with 10 nodes per element.
TEST(FbprepOrder2, SlenderBeamMeetsTimoshenkoWhereLinearTetrahedraLock) {
  const auto dir = flexbody::test::scratch_dir();
  fp::PrepOptions quadratic = beam(2, dir, "beam2.fbh5");
  quadratic.interfaces.push_back({"tip", end_face(1.0), "rbe3", "interface"});
  const fp::PrepSummary q = fp::run_fbprep(quadratic);
  const fp::PrepSummary l = fp::run_fbprep(beam(1, dir, "beam1.fbh5"));
  std::printf("first bending pair against Timoshenko: quadratic %ld DOFs %+.3g %%, linear %ld DOFs %+.3g %%\n",
              static_cast<long>(q.dofs), 100 * pair_error(q.frequencies_hz, kFreeFree), static_cast<long>(l.dofs),
              100 * pair_error(l.frequencies_hz, kFreeFree));
  EXPECT_EQ(q.element_order, 2);
  EXPECT_EQ(l.element_order, 1);
  EXPECT_EQ(q.dofs, 3 * q.nodes);
  EXPECT_LT(std::abs(pair_error(q.frequencies_hz, kFreeFree)), 2e-3);
  EXPECT_GT(pair_error(l.frequencies_hz, kFreeFree), 0.3);

  const flexbody::format::BodyData body = flexbody::format::read_body_file(quadratic.output);
  EXPECT_EQ(body.mesh.element_order, 2);
  ASSERT_EQ(body.mesh.tets.cols(), 10);
  EXPECT_EQ(body.mesh.nodes.rows(), q.nodes);
  EXPECT_EQ(body.mesh.surface_triangles.rows(), q.surface_triangles);
  ASSERT_EQ(body.interfaces.size(), 1u);
  const flexbody::format::Interface& tip = body.interfaces[0];
  const Eigen::Vector3d com = body.mass.center_of_mass_input;
  Eigen::Index on_face = 0;
  for (Eigen::Index i = 0; i < body.mesh.nodes.rows(); ++i) on_face += std::abs(body.mesh.nodes(i, 0) + com.x() - 1.0) < 1e-9;
  EXPECT_EQ(tip.nodes.size(), on_face);
  EXPECT_GT(on_face, 9);  // one element across: 4 corners and at least 5 edge nodes on the face
  EXPECT_LT((tip.reference_point + com - Eigen::Vector3d(1.0, 0.025, 0.025)).norm(), 1e-12);
  EXPECT_GT(tip.weights.minCoeff(), 0.0);
  ASSERT_EQ(body.recovery.size(), 1u);
  EXPECT_EQ(body.recovery[0].nodes.size(), body.mesh.nodes.rows());

  // The reader bounds every stress mode by what the mesh's stiffest quadratic element can make of its field
  // (SCHEMA.md, Validity): fbprep's values pass, one made 100 times larger does not.
  flexbody::format::BodyData damaged = body;
  Eigen::Index row = 0, column = 0;
  (void)damaged.recovery[0].stress_modes.cwiseAbs().maxCoeff(&row, &column);
  damaged.recovery[0].stress_modes(row, column) *= 100.0;
  try {
    flexbody::format::validate(damaged);
    ADD_FAILURE() << "an inflated stress mode was accepted";
  } catch (const flexbody::format::BodyFileError& e) {
    EXPECT_NE(std::string(e.what()).find("the most that the mesh's stiffest element can make of field"), std::string::npos)
        << e.what();
  }
}

// Craig-Bampton with the root face clamped (rbe2): every node of the face, mid-edge nodes included, is tied, so the
// clamped beam's first pair is the cantilever's. Measured: quadratic +0.43 % (a rigidly clamped 3D face is stiffer than
// Timoshenko's clamp), linear +61 %. Asserted: quadratic within 1 %, linear above 30 %.
TEST(FbprepOrder2, CraigBamptonClampsEveryNodeOfTheRootFace) {
  const auto dir = flexbody::test::scratch_dir();
  double errors[2] = {0.0, 0.0};
  for (const int order : {1, 2}) {
    fp::PrepOptions options = beam(order, dir, "cantilever.fbh5");
    options.reduction = fp::ReductionKind::craig_bampton;
    options.interfaces.push_back({"root", end_face(0.0), "rbe2", "interface"});
    const fp::PrepSummary s = fp::run_fbprep(options);
    errors[order - 1] = pair_error(s.fixed_interface_frequencies_hz, kCantilever);
    std::printf("order %d, %ld DOFs: clamped first pair %+.3g %% off Timoshenko\n", order, static_cast<long>(s.dofs),
                100 * errors[order - 1]);
  }
  EXPECT_LT(std::abs(errors[1]), 1e-2);
  EXPECT_GT(errors[0], 0.3);
}

// A CAD surface selector takes the same patch as a plane through that face: gmsh's 6-node surface triangles are split
// into four like the body file's boundary (mesh_topology.hpp), so the same nodes with the same weights (the x = 1 face
// of OpenCASCADE's box is its surface 2).
TEST(FbprepOrder2, SurfaceTagsSelectTheSamePatchAsAPlane) {
  const auto dir = flexbody::test::scratch_dir();
  flexbody::format::Interface by[2];
  for (int k = 0; k < 2; ++k) {
    fp::PrepOptions options = beam(2, dir, "tip.fbh5");
    options.modes.modes = 1;
    options.interfaces.push_back({"tip", k == 0 ? fp::Selector(end_face(1.0)) : fp::Selector(fp::SurfaceSelector{{2}}),
                                  "rbe3", "interface"});
    (void)fp::run_fbprep(options);
    by[k] = flexbody::format::read_body_file(options.output).interfaces.at(0);
  }
  ASSERT_EQ(by[0].nodes, by[1].nodes);
  EXPECT_LT((by[0].weights - by[1].weights).cwiseAbs().maxCoeff(), 1e-15);
}

// The sample bracket at its spec's 3 mm with quadratic elements has 16 619 nodes: the whole body's stress modes (12
// modes, 36 fields) would take 86 MB, above the 64 MB default, its 8 556 boundary nodes' 44 MB. So the default output
// region is the surface, which is what fbsim's ParaView frames draw: a pendulum scene with pictures runs on the body,
// and its frames hold the surface's nodes with their stresses.
TEST(FbprepOrder2, LargeBodiesRecoverStressesOnTheirSurfaceByDefault) {
  const auto dir = flexbody::test::scratch_dir();
  const std::filesystem::path meshes = std::filesystem::path(FLEXBODY_SOURCE_DIR) / "meshes";
  std::filesystem::copy_file(meshes / "bracket.step", dir / "bracket.step");
  std::filesystem::copy_file(meshes / "bracket.yaml", dir / "bracket.yaml");
  const flexbody::test::CliRun prep = flexbody::test::run_fbprep(dir, "bracket.yaml -o bracket.fbh5 --order 2 -q");
  ASSERT_EQ(prep.exit_code, 0) << prep.err;
  const flexbody::format::BodyData body = flexbody::format::read_body_file(dir / "bracket.fbh5");
  ASSERT_EQ(body.recovery.size(), 1u);
  EXPECT_EQ(body.recovery[0].name, "surface");
  std::vector<int> boundary(body.mesh.surface_triangles.data(),
                            body.mesh.surface_triangles.data() + body.mesh.surface_triangles.size());
  std::sort(boundary.begin(), boundary.end());
  boundary.erase(std::unique(boundary.begin(), boundary.end()), boundary.end());
  ASSERT_EQ(body.recovery[0].nodes.size(), static_cast<Eigen::Index>(boundary.size()));
  EXPECT_TRUE(std::equal(boundary.begin(), boundary.end(), body.recovery[0].nodes.data()));
  EXPECT_LT(body.recovery[0].nodes.size(), body.mesh.nodes.rows());

  std::ofstream(dir / "pendulum.yaml")
      << "bodies:\n  bracket: {file: bracket.fbh5, modes: 6}\n"
         "joints:\n  pivot: {type: revolute, body: bracket, interface: bore_1, to: ground, axis: [0, 0, 1]}\n"
         "gravity: [0, -9.81, 0]\n"
         "integrator: {type: generalized-alpha, rho_inf: 0.9, step: 1.0e-3, end: 0.01}\n"
         "paraview: {bodies: [bracket], every: 5}\n";
  const flexbody::test::CliRun sim = flexbody::test::run_fbsim(dir, "pendulum.yaml -o out -q");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "bracket.pvd"));
  std::ifstream frame_file(dir / "out" / "bracket" / "bracket_000000.vtu");
  const std::string frame((std::istreambuf_iterator<char>(frame_file)), std::istreambuf_iterator<char>());
  EXPECT_NE(frame.find("NumberOfPoints=\"" + std::to_string(boundary.size()) + "\""), std::string::npos);
  EXPECT_NE(frame.find("Name=\"von_mises\""), std::string::npos);
  EXPECT_NE(frame.find("Name=\"stress\""), std::string::npos);
}

// Unit loads and static corrections on quadratic tetrahedra: the cantilever beam, its root face clamped (every node of
// it, mid-edge nodes included, held), 1000 N across its axis spread over the tip face by the load point's tributary
// weights (static_correction.hpp). Its tip marker deflects by 3.0476e-3 m in Timoshenko's beam (validation/README.md);
// measured with quadratic elements at 0.05 m (one element through the thickness) 3.034e-3 (-0.45 %: the rigid 3D
// clamp is stiffer), with linear ones 1.076e-3 (-65 %). Asserted: quadratic within 1.5 %, linear more than 30 % short. The
// Craig-Bampton basis with that load point's static correction holds the clamped response to 1e-8 (what the reduction
// promises, SCHEMA.md).
TEST(FbprepOrder2, TipLoadDeflectsTheCantileverAsTimoshenkoSays) {
  constexpr double kDeflection = 3.0476e-3, kForce = 1000.0;  // m, N
  double deflection[2] = {0.0, 0.0};
  for (const int order : {1, 2}) {
    fp::GmshImportOptions options;
    options.unit = fp::LengthUnit::metre;
    options.mesh_size = 0.05;
    options.order = order;
    const fp::ImportedMesh imported =
        fp::import_tet_mesh(flexbody::test::data_dir() / "gmsh-beam" / "beam_1m.geo", options);
    fp::RowMatrixX3d nodes;
    fp::SparseMatrix k, m;
    fp::RowMatrixX3i boundary;
    const fp::Material steel{"steel", 210e9, 0.3, 7850.0};
    if (order == 2) {
      nodes = imported.quadratic->nodes;
      fp::Tet10Matrices fe = fp::assemble_tet10(*imported.quadratic, steel);
      k = std::move(fe.stiffness);
      m = std::move(fe.scalar_mass);
      boundary = fp::boundary_triangles(*imported.quadratic);
    } else {
      nodes = imported.mesh.nodes;
      const fp::NodeGraph graph = fp::NodeGraph::build(imported.mesh);
      const auto geometry = fp::element_geometries(imported.mesh);
      k = fp::assemble_stiffness(imported.mesh, graph, geometry, steel);
      m = fp::assemble_scalar_mass(imported.mesh, graph, geometry, steel.density, fp::MassScheme::consistent);
      boundary = fp::boundary_triangles(imported.mesh);
    }
    const fp::SurfacePatch root = fp::select_surface_patch("root", end_face(0.0), nodes, boundary);
    const fp::SurfacePatch tip = fp::select_surface_patch("tip", end_face(1.0), nodes, boundary);
    const fp::LoadPoint load{"tip", tip.nodes, tip.weights, fp::patch_centroid(tip, nodes),
                             {false, true, false, false, false, false}};
    const Eigen::VectorXd f = kForce * fp::unit_load_vectors(nodes, {load}).col(0);
    std::vector<char> held(static_cast<std::size_t>(nodes.rows()), 0);
    for (const int i : root.nodes) held[static_cast<std::size_t>(i)] = 1;
    std::vector<Eigen::Index> free;
    for (Eigen::Index i = 0; i < nodes.rows(); ++i)
      if (!held[static_cast<std::size_t>(i)])
        for (int c = 0; c < 3; ++c) free.push_back(3 * i + c);
    const Eigen::SparseMatrix<double> full = fp::full_from_upper(k);
    Eigen::SparseMatrix<double> clamped(static_cast<Eigen::Index>(free.size()), static_cast<Eigen::Index>(free.size()));
    {
      std::vector<Eigen::Index> where(static_cast<std::size_t>(full.rows()), -1);
      for (std::size_t r = 0; r < free.size(); ++r) where[static_cast<std::size_t>(free[r])] = static_cast<Eigen::Index>(r);
      std::vector<Eigen::Triplet<double>> entries;
      for (Eigen::Index c = 0; c < full.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(full, c); it; ++it)
          if (where[static_cast<std::size_t>(it.row())] >= 0 && where[static_cast<std::size_t>(c)] >= 0)
            entries.emplace_back(where[static_cast<std::size_t>(it.row())], where[static_cast<std::size_t>(c)], it.value());
      clamped.setFromTriplets(entries.begin(), entries.end());
    }
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(clamped);
    ASSERT_EQ(solver.info(), Eigen::Success);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(full.rows());
    const Eigen::VectorXd rhs = f(free);  // a plain vector: SimplicialLDLT solving into an indexed view went wrong
    const Eigen::VectorXd clamped_u = solver.solve(rhs);
    ASSERT_LT((clamped * clamped_u - rhs).norm(), 1e-8 * rhs.norm());  // measured 1e-9: rounding times K's condition
    u(free) = clamped_u;
    for (Eigen::Index j = 0; j < tip.nodes.size(); ++j) deflection[order - 1] += tip.weights(j) * u(3 * tip.nodes(j) + 1);

    if (order == 2) {  // the Craig-Bampton basis with the tip's static correction holds u, up to rigid-body fields
      fp::CraigBamptonOptions cb_options;
      cb_options.fixed_interface_modes = 3;
      const fp::CraigBamptonModes cb = fp::craig_bampton_modes(
          nodes, k, m, steel, {{root.nodes, fp::patch_centroid(root, nodes)}}, cb_options, f / kForce);
      Eigen::MatrixXd basis(full.rows(), 6 + cb.vectors.cols());
      basis << fp::rigid_body_modes(nodes, m), cb.vectors;
      const Eigen::VectorXd fitted = basis * basis.colPivHouseholderQr().solve(u);
      EXPECT_LT((u - fitted).norm(), 1e-8 * u.norm());
    }
  }
  std::printf("tip deflection under %.0f N: linear %.4g m, quadratic %.4g m (Timoshenko %.4g m)\n", kForce,
              deflection[0], deflection[1], kDeflection);
  EXPECT_LT(std::abs(deflection[1] / kDeflection - 1.0), 1.5e-2);
  EXPECT_LT(deflection[0] / kDeflection, 0.7);
}

// A .msh that already holds quadratic tetrahedra (tests/data/gmsh-beam/beam_1m_order2.msh, gmsh 4.8's own second-order
// mesh of the beam at 0.05 m) is read as it is, by default (the order a .msh holds) and with --order 2; asked for
// linear tetrahedra, fbprep says it has quadratic ones, and writes nothing. Its first bending pair is within 0.2 % of
// Timoshenko (as the .geo's).
TEST(FbprepOrder2, ReadsAQuadraticMshAsItIs) {
  const auto dir = flexbody::test::scratch_dir();
  const std::filesystem::path msh = flexbody::test::data_dir() / "gmsh-beam" / "beam_1m_order2.msh";
  const flexbody::test::CliRun run =
      flexbody::test::run_fbprep(dir, fmt::format("'{}' --unit m --order 2 --modes 2 -o q.fbh5 --json", msh.string()));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const flexbody::format::BodyData body = flexbody::format::read_body_file(dir / "q.fbh5");
  EXPECT_EQ(body.mesh.element_order, 2);
  EXPECT_LT(std::abs(pair_error(body.modes.frequencies_hz, kFreeFree)), 2e-3);
  const flexbody::test::CliRun by_default =
      flexbody::test::run_fbprep(dir, fmt::format("'{}' --unit m --modes 2 -o d.fbh5", msh.string()));
  ASSERT_EQ(by_default.exit_code, 0) << by_default.err;
  EXPECT_EQ(flexbody::format::read_body_file(dir / "d.fbh5").mesh.element_order, 2);
  const flexbody::test::CliRun linear =
      flexbody::test::run_fbprep(dir, fmt::format("'{}' --unit m --order 1 --modes 2 -o l.fbh5", msh.string()));
  EXPECT_EQ(linear.exit_code, 1);
  EXPECT_NE(linear.err.find("the mesh has no linear tetrahedra (it has quadratic ones: ask for order 2 to read them)"),
            std::string::npos) << linear.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "l.fbh5"));
}
