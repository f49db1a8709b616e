// The linear tetrahedron and the global assembly: against Abaqus' exported matrices, the patch test,
// and the rigid-body null space.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"
#include "test_meshes.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <omp.h>

#include <random>

namespace fp = flexbody::preprocess;
using flexbody::test::box_mesh;

namespace {

using flexbody::test::assemble;

double max_abs(const fp::SparseMatrix& m) {
  double v = 0.0;
  for (Eigen::Index j = 0; j < m.outerSize(); ++j)
    for (fp::SparseMatrix::InnerIterator it(m, j); it; ++it) v = std::max(v, std::abs(it.value()));
  return v;
}

fp::SparseMatrix vector_mass(const fp::SparseMatrix& scalar_full) {
  std::vector<Eigen::Triplet<double, std::int64_t>> t;
  for (Eigen::Index j = 0; j < scalar_full.outerSize(); ++j)
    for (fp::SparseMatrix::InnerIterator it(scalar_full, j); it; ++it)
      for (int c = 0; c < 3; ++c) t.emplace_back(3 * it.row() + c, 3 * j + c, it.value());
  fp::SparseMatrix m(3 * scalar_full.rows(), 3 * scalar_full.cols());
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

// A box mesh whose interior nodes are moved randomly (by up to 20 % of a cell): an irregular patch.
fp::TetMesh irregular_box() {
  fp::TetMesh mesh = box_mesh(1.0, 0.6, 0.4, 5, 3, 2);
  std::mt19937 generator(7);
  std::uniform_real_distribution<double> jitter(-0.04, 0.04);
  for (Eigen::Index i = 0; i < mesh.node_count(); ++i) {
    const auto x = mesh.nodes.row(i);
    const bool interior = x(0) > 1e-9 && x(0) < 1.0 - 1e-9 && x(1) > 1e-9 && x(1) < 0.6 - 1e-9 && x(2) > 1e-9 &&
                          x(2) < 0.4 - 1e-9;
    if (interior)
      for (int c = 0; c < 3; ++c) mesh.nodes(i, c) += jitter(generator);
  }
  return mesh;
}

}  // namespace

const fp::Material kAbaqusSteel{"abaqus", 2e11, 0.3, 2900.0};  // blockC3D4.inp: *Elastic 2e11, 0.3; *Density 2900

TEST(Tet4Assembly, StiffnessEqualsAbaqusExport) {
  const auto dir = flexbody::test::data_dir() / "abaqus-block";
  const auto a = assemble(flexbody::test::read_abaqus_c3d4(dir / "blockC3D4.inp"), kAbaqusSteel, fp::MassScheme::consistent);
  ASSERT_EQ(a.mesh.node_count(), 214);
  ASSERT_EQ(a.mesh.element_count(), 767);
  const fp::SparseMatrix abaqus = flexbody::test::read_abaqus_matrix(dir / "blockC3D4_STIF1.mtx", a.mesh.dof_count());
  const fp::SparseMatrix ours = fp::full_from_upper(a.stiffness);
  // Abaqus prints 16 significant digits; the same element on the same coordinates agrees to round-off.
  const double difference = max_abs(fp::SparseMatrix(ours - abaqus));
  EXPECT_LT(difference / max_abs(abaqus), 1e-12) << "max |K - K_abaqus| = " << difference;
}

TEST(Tet4Assembly, RowSumLumpedMassEqualsAbaqusExport) {
  const auto dir = flexbody::test::data_dir() / "abaqus-block";
  const auto a = assemble(flexbody::test::read_abaqus_c3d4(dir / "blockC3D4.inp"), kAbaqusSteel, fp::MassScheme::lumped);
  const fp::SparseMatrix abaqus = flexbody::test::read_abaqus_matrix(dir / "blockC3D4_MASS1.mtx", a.mesh.dof_count());
  const fp::SparseMatrix ours = vector_mass(fp::full_from_upper(a.scalar_mass));
  EXPECT_LT(max_abs(fp::SparseMatrix(ours - abaqus)) / max_abs(abaqus), 1e-12);
  // Row-sum lumping of the consistent mass gives the same matrix.
  const auto consistent = assemble(a.mesh, kAbaqusSteel, fp::MassScheme::consistent);
  const Eigen::VectorXd row_sums = fp::full_from_upper(consistent.scalar_mass) * Eigen::VectorXd::Ones(214);
  const Eigen::VectorXd lumped = fp::full_from_upper(a.scalar_mass).diagonal();
  EXPECT_LT((row_sums - lumped).cwiseAbs().maxCoeff() / lumped.maxCoeff(), 1e-13);
  EXPECT_NEAR(row_sums.sum(), 11600.0, 11600.0 * 1e-6);  // 4 m^3 x 2900 kg/m^3; coordinates are single precision
}

TEST(Tet4Assembly, VectorMassProductEqualsTheKroneckerMatrix) {
  // apply_vector_mass reads M_s's upper triangle once: compare with the explicit symmetric M_s ⊗ I3.
  const auto a = assemble(irregular_box(), kAbaqusSteel, fp::MassScheme::consistent);
  const fp::SparseMatrix m = vector_mass(fp::full_from_upper(a.scalar_mass));
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd x(a.mesh.dof_count()), y(a.mesh.dof_count());
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = uniform(random);
  fp::apply_vector_mass(a.scalar_mass, x, y);
  const Eigen::VectorXd expected = m * x;
  // The same products summed in another order: round-off of the largest entry.
  EXPECT_LT((y - expected).cwiseAbs().maxCoeff(), 1e-14 * expected.cwiseAbs().maxCoeff());
}

TEST(Tet4Assembly, SymmetricProductOfTheWholeMatrixEqualsTheUpperTriangles) {
  // symmetric_product (rows on all threads, both triangles stored) against Eigen's product with the upper triangle.
  const auto a = assemble(irregular_box(), kAbaqusSteel, fp::MassScheme::consistent);
  const Eigen::MatrixXd x = Eigen::MatrixXd::Random(a.scalar_mass.rows(), 5);
  const Eigen::MatrixXd expected = a.scalar_mass.selfadjointView<Eigen::Upper>() * x;
  const Eigen::MatrixXd y = fp::symmetric_product(fp::full_from_upper(a.scalar_mass), x);
  EXPECT_LT((y - expected).cwiseAbs().maxCoeff(), 1e-14 * expected.cwiseAbs().maxCoeff());  // summation order only
  EXPECT_THROW((void)fp::symmetric_product(fp::full_from_upper(a.scalar_mass), Eigen::MatrixXd(3, 2)), std::logic_error);
}

TEST(Tet4Assembly, StiffnessAnnihilatesRigidBodyFields) {
  const auto a = assemble(irregular_box(), kAbaqusSteel, fp::MassScheme::consistent);
  const Eigen::MatrixXd rigid = fp::rigid_body_modes(a.mesh.nodes, a.scalar_mass);
  const fp::SparseMatrix k = fp::full_from_upper(a.stiffness);
  for (int mode = 0; mode < 6; ++mode) {
    SCOPED_TRACE(mode);
    // Each entry of K r cancels terms of size |K| |r|: the remainder is round-off, ~1e-16 of it.
    EXPECT_LT((k * rigid.col(mode)).norm() / (max_abs(k) * rigid.col(mode).norm()), 1e-13);
  }
}

TEST(Tet4Assembly, PatchTestLinearFieldGivesConstantStrainAndEquilibrium) {
  const auto a = assemble(irregular_box(), kAbaqusSteel, fp::MassScheme::consistent);
  const Eigen::Index n = a.mesh.node_count();
  Eigen::Matrix3d gradient;
  gradient << 1e-3, 2e-4, -3e-4, 5e-4, -7e-4, 1e-4, -2e-4, 3e-4, 6e-4;
  const Eigen::Vector3d offset(1e-3, -2e-3, 5e-4);
  Eigen::VectorXd u(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) u.segment<3>(3 * i) = offset + gradient * a.mesh.nodes.row(i).transpose();

  // Every element sees exactly the prescribed strain.
  const Eigen::Matrix3d strain = 0.5 * (gradient + gradient.transpose());
  const auto geometry = fp::element_geometries(a.mesh);
  for (Eigen::Index e = 0; e < a.mesh.element_count(); ++e) {
    Eigen::Matrix3d du = Eigen::Matrix3d::Zero();
    for (int c = 0; c < 4; ++c) du += u.segment<3>(3 * a.mesh.tets(e, c)) * geometry[e].gradients.row(c);
    ASSERT_LT((0.5 * (du + du.transpose()) - strain).norm(), 1e-14 * strain.norm() * 1e3) << "element " << e;
  }

  // Interior nodes are in equilibrium: (K u)_i = 0 away from the boundary.
  const fp::SparseMatrix k = fp::full_from_upper(a.stiffness);
  const Eigen::VectorXd f = k * u;
  std::vector<Eigen::Index> interior, boundary;
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto x = a.mesh.nodes.row(i);
    const bool on_boundary = x(0) < 1e-9 || x(0) > 1.0 - 1e-9 || x(1) < 1e-9 || x(1) > 0.6 - 1e-9 || x(2) < 1e-9 ||
                             x(2) > 0.4 - 1e-9;
    (on_boundary ? boundary : interior).push_back(i);
  }
  ASSERT_FALSE(interior.empty());
  double worst = 0.0;
  for (Eigen::Index i : interior) worst = std::max(worst, f.segment<3>(3 * i).norm());
  EXPECT_LT(worst / (max_abs(k) * u.norm()), 1e-14);

  // Prescribing the field on the boundary and solving for the interior reproduces it there.
  std::vector<Eigen::Index> dof_of(3 * n, -1);
  Eigen::Index m = 0;
  for (Eigen::Index i : interior)
    for (int c = 0; c < 3; ++c) dof_of[3 * i + c] = m++;
  std::vector<Eigen::Triplet<double>> t;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
  for (Eigen::Index j = 0; j < k.outerSize(); ++j)
    for (fp::SparseMatrix::InnerIterator it(k, j); it; ++it) {
      if (dof_of[it.row()] < 0) continue;
      if (dof_of[j] >= 0) t.emplace_back(dof_of[it.row()], dof_of[j], it.value());
      else rhs(dof_of[it.row()]) -= it.value() * u(j);
    }
  Eigen::SparseMatrix<double> kii(m, m);
  kii.setFromTriplets(t.begin(), t.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(kii);
  const Eigen::VectorXd ui = solver.solve(rhs);
  double error = 0.0;
  for (Eigen::Index i : interior) error = std::max(error, (ui.segment<3>(dof_of[3 * i]) - u.segment<3>(3 * i)).norm());
  EXPECT_LT(error / u.cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Tet4Assembly, ResultDoesNotDependOnThreadCount) {
  const fp::TetMesh mesh = irregular_box();
  const auto graph = fp::NodeGraph::build(mesh);
  const auto geometry = fp::element_geometries(mesh);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const fp::SparseMatrix serial = fp::assemble_stiffness(mesh, graph, geometry, kAbaqusSteel);
  omp_set_num_threads(std::max(2, threads));
  const fp::SparseMatrix parallel = fp::assemble_stiffness(mesh, graph, geometry, kAbaqusSteel);
  omp_set_num_threads(threads);
  ASSERT_EQ(serial.nonZeros(), parallel.nonZeros());
  EXPECT_TRUE(std::equal(serial.valuePtr(), serial.valuePtr() + serial.nonZeros(), parallel.valuePtr()));
}
