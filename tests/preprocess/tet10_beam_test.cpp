// Issue 15's reason for quadratic tetrahedra: linear ones lock in bending. The free-free steel beam
// 1 x 0.05 x 0.05 m (validation/README.md: Timoshenko's first bending pair at 263.46 Hz) on structured Kuhn-split
// box meshes: linear elements, and the same meshes made quadratic (quadratic_mesh, straight edges), assembled by
// assemble_tet10 and solved by the pipeline's free-free eigensolver.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"
#include "test_meshes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};
constexpr double kTimoshenko = 263.46;  // Hz, first free-free bending pair

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
