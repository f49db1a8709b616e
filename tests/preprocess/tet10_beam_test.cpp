// Issue 15's reason for quadratic tetrahedra: linear ones lock in bending. The free-free (and the clamped) steel beam
// 1 x 0.05 x 0.05 m (validation/README.md: Timoshenko's first bending pair at 263.46 Hz) on structured Kuhn-split
// box meshes: linear elements, and the same meshes made quadratic (quadratic_mesh, straight edges), assembled by
// assemble_tet10 and solved by the pipeline's free-free eigensolver.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"
#include "test_meshes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};
constexpr double kTimoshenko = 263.46;  // Hz, first free-free bending pair
constexpr double kCantilever = 41.694;  // Hz, Timoshenko's first cantilever pair

struct Frequency {
  Eigen::Index dofs = 0;
  double error = 0.0;  ///< mean of the first two elastic frequencies (the bending pair) against Timoshenko
};

Frequency first_pair(const fp::RowMatrixX3d& nodes, const fp::SparseMatrix& k, const fp::SparseMatrix& m) {
  fp::FreeFreeOptions options;
  options.modes = 2;
  const fp::FreeFreeModes modes = fp::free_free_modes(nodes, k, m, kSteel, options);
  return {3 * nodes.rows(), 0.5 * (modes.frequencies_hz(0) + modes.frequencies_hz(1)) / kTimoshenko - 1.0};
}

Frequency linear(int nx, int n) {
  const auto a = flexbody::test::assemble(flexbody::test::box_mesh(1.0, 0.05, 0.05, nx, n, n), kSteel);
  return first_pair(a.mesh.nodes, a.stiffness, a.scalar_mass);
}

Frequency quadratic(int nx, int n) {
  const fp::Tet10Mesh mesh = fp::quadratic_mesh(flexbody::test::box_mesh(1.0, 0.05, 0.05, nx, n, n));
  const fp::Tet10Matrices a = fp::assemble_tet10(mesh, kSteel);
  return first_pair(mesh.nodes, a.stiffness, a.scalar_mass);
}

// The first pair with the face x = 0 held rigidly (Craig-Bampton's fixed-interface problem of an rbe2 root: every
// node of the face, mid-edge nodes included, clamped), against Timoshenko's cantilever.
template <class Mesh>
Frequency clamped_pair(const Mesh& mesh, const fp::SparseMatrix& k, const fp::SparseMatrix& m) {
  fp::RigidInterface root;
  std::vector<int> face;
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i)
    if (mesh.nodes(i, 0) == 0.0) face.push_back(static_cast<int>(i));
  root.nodes = Eigen::Map<const Eigen::VectorXi>(face.data(), static_cast<Eigen::Index>(face.size()));
  root.reference_point = Eigen::Vector3d(0.0, 0.025, 0.025);
  fp::CraigBamptonOptions options;
  options.fixed_interface_modes = 2;
  const fp::CraigBamptonModes cb = fp::craig_bampton_modes(mesh.nodes, k, m, kSteel, {root}, options);
  const Eigen::VectorXd& f = cb.fixed_interface_frequencies_hz;
  return {3 * mesh.nodes.rows(), 0.5 * (f(0) + f(1)) / kCantilever - 1.0};
}

Frequency clamped_linear(int nx, int n) {
  const auto a = flexbody::test::assemble(flexbody::test::box_mesh(1.0, 0.05, 0.05, nx, n, n), kSteel);
  return clamped_pair(a.mesh, a.stiffness, a.scalar_mass);
}

Frequency clamped_quadratic(int nx, int n) {
  const fp::Tet10Mesh mesh = fp::quadratic_mesh(flexbody::test::box_mesh(1.0, 0.05, 0.05, nx, n, n));
  const fp::Tet10Matrices a = fp::assemble_tet10(mesh, kSteel);
  return clamped_pair(mesh, a.stiffness, a.scalar_mass);
}

}  // namespace

// Measured (mean of the pair against Timoshenko): linear 40 x 2 x 2 cells (1 107 DOFs) +41.9 %, 80 x 4 x 4 (6 075)
// +12.4 %, 160 x 8 x 8 (39 123) +3.3 %, falling 3.4 and 3.8 times per halving of the cell (h², locking); quadratic
// 10 x 1 x 1 (567 DOFs) +0.41 %, 20 x 2 x 2 (3 075) +0.047 %, 40 x 4 x 4 (19 683) +0.013 %, where the model
// difference between 3D elasticity and Timoshenko's beam takes over. At a tenth of the DOFs the quadratic mesh is 30
// times closer. The bounds are 1.5 times the measured quadratic errors and 80 % of the linear ones' ratios.
TEST(Tet10Beam, QuadraticTetrahedraDoNotLockInBending) {
  const Frequency l[3] = {linear(40, 2), linear(80, 4), linear(160, 8)};
  const Frequency q[3] = {quadratic(10, 1), quadratic(20, 2), quadratic(40, 4)};
  for (int k = 0; k < 3; ++k)
    std::printf("linear %6ld DOFs %+.5f   quadratic %6ld DOFs %+.6f\n", static_cast<long>(l[k].dofs), l[k].error,
                static_cast<long>(q[k].dofs), q[k].error);
  EXPECT_LT(std::abs(q[0].error), 6e-3);
  EXPECT_LT(std::abs(q[1].error), 7e-4);
  EXPECT_LT(std::abs(q[2].error), 2e-4);
  ASSERT_GT(l[1].dofs, 10 * q[0].dofs);
  EXPECT_GT(l[1].error, 0.1);  // the linear mesh with ten times the DOFs, still locked
  EXPECT_GT(l[0].error, 2.7 * l[1].error);
  EXPECT_GT(l[1].error, 3.0 * l[2].error);
}

// The same beam clamped at x = 0 (a rigid root face) against Timoshenko's cantilever pair, 41.694 Hz. Measured:
// quadratic 567, 3 075, 19 683 DOFs +1.50 %, +0.578 %, +0.334 %; linear 1 107, 6 075, 39 123 DOFs +42.5 %, +12.8 %,
// +3.59 %. A rigidly held 3D face is stiffer than Timoshenko's clamp (it also stops the face's Poisson contraction and
// warping), so the quadratic sequence converges to a little above it (its steps shrink: 0.92, then 0.24 points).
// Asserted: the quadratic errors fall and stay within 1.5 times the measured ones; the linear mesh with 10 times the
// DOFs of the coarsest quadratic one is 5 times further off (8.5 measured); linear errors fall by at least 2.7 per
// halving.
TEST(Tet10Beam, ClampedBeamConvergesWithTheMesh) {
  const Frequency l[3] = {clamped_linear(40, 2), clamped_linear(80, 4), clamped_linear(160, 8)};
  const Frequency q[3] = {clamped_quadratic(10, 1), clamped_quadratic(20, 2), clamped_quadratic(40, 4)};
  for (int k = 0; k < 3; ++k)
    std::printf("clamped: linear %6ld DOFs %+.5f   quadratic %6ld DOFs %+.6f\n", static_cast<long>(l[k].dofs),
                l[k].error, static_cast<long>(q[k].dofs), q[k].error);
  EXPECT_LT(q[0].error, 2.3e-2);
  EXPECT_LT(q[1].error, 8.7e-3);
  EXPECT_LT(q[2].error, 5e-3);
  EXPECT_GT(q[0].error, q[1].error);
  EXPECT_GT(q[1].error, q[2].error);
  EXPECT_GT(q[2].error, 0.0);  // stiffer than Timoshenko, from above
  ASSERT_GT(l[1].dofs, 10 * q[0].dofs);
  EXPECT_GT(l[1].error, 5.0 * q[0].error);
  EXPECT_GT(l[0].error, 2.7 * l[1].error);
  EXPECT_GT(l[1].error, 2.7 * l[2].error);
}
