// The quadratic tetrahedron (formats/tet10_element.hpp, issue 15) against Abaqus' C3D10 on the same mesh, the closed
// form of its consistent mass, and patch tests: quadratic fields are represented exactly, rigid motions are free of
// strain, a linear field is recovered exactly by a solve.
#include "flexbody/format/tet10_element.hpp"
#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace fmt10 = flexbody::format;
namespace fp = flexbody::preprocess;

namespace {

// A straight-sided element: its mid-edge nodes at their edges' middles.
fmt10::Tet10Nodes straight(const Eigen::Matrix<double, 4, 3>& corners) {
  fmt10::Tet10Nodes x;
  x.topRows<4>() = corners;
  for (int e = 0; e < 6; ++e) {
    const auto [i, j] = fmt10::kTet10Edges[static_cast<std::size_t>(e)];
    x.row(4 + e) = 0.5 * (corners.row(i) + corners.row(j));
  }
  return x;
}

Eigen::Matrix<double, 4, 3> some_corners() {
  Eigen::Matrix<double, 4, 3> c;
  c << 0.1, -0.2, 0.05, 1.3, 0.1, -0.1, 0.2, 0.9, 0.15, 0.4, 0.3, 1.1;
  return c;
}

double volume(const Eigen::Matrix<double, 4, 3>& c) {
  Eigen::Matrix3d j;
  for (int a = 0; a < 3; ++a) j.col(a) = (c.row(a + 1) - c.row(0)).transpose();
  return j.determinant() / 6.0;
}

// A C3D10 mesh assembled by the pipeline's assemble_tet10, then made dense (the block's 771 DOFs) with M̄ = M_s ⊗ I3.
struct Assembled {
  Eigen::MatrixXd stiffness, mass;
};
Assembled assemble(const fp::Tet10Mesh& mesh, const fp::Material& material) {
  const fp::Tet10Matrices m = fp::assemble_tet10(mesh, material);
  Assembled a{Eigen::MatrixXd(fp::full_from_upper(m.stiffness)), Eigen::MatrixXd::Zero(3 * mesh.node_count(), 3 * mesh.node_count())};
  const Eigen::MatrixXd m_s(fp::full_from_upper(m.scalar_mass));
  for (Eigen::Index i = 0; i < m_s.rows(); ++i)
    for (Eigen::Index j = 0; j < m_s.cols(); ++j) a.mass.block<3, 3>(3 * i, 3 * j).diagonal().setConstant(m_s(i, j));
  return a;
}

const fp::Material kAbaqusSteel{"abaqus", 2e11, 0.3, 2900.0};  // blockC3D10.inp: *Elastic 2e11, 0.3; *Density 2900

}  // namespace

// ρ ∫ N_a N_b dV of a straight element in closed form, ρV/420 times: 6 on a corner's diagonal and 1 between corners,
// −4 between a corner and an edge through it and −6 otherwise, 32 on an edge's diagonal, 16 between edges that share
// a corner and 8 between opposite edges (the entries sum to 420: the mass). The quadrature must give it to round-off.
TEST(Tet10Element, ConsistentMassEqualsTheClosedForm) {
  const Eigen::Matrix<double, 4, 3> c = some_corners();
  const double rho = 2700.0, v = volume(c);
  const Eigen::Matrix<double, 10, 10> m = fmt10::tet10_mass(straight(c), rho);
  auto shares = [](int a, int b) {  // nodes a and b (0..9) have a corner in common
    auto corners = [](int k) { return k < 4 ? std::array<int, 2>{k, k} : fmt10::kTet10Edges[static_cast<std::size_t>(k - 4)]; };
    const auto p = corners(a), q = corners(b);
    return p[0] == q[0] || p[0] == q[1] || p[1] == q[0] || p[1] == q[1];
  };
  double worst = 0.0;
  for (int a = 0; a < 10; ++a)
    for (int b = 0; b < 10; ++b) {
      double pattern = 0.0;
      if (a < 4 && b < 4) pattern = a == b ? 6.0 : 1.0;
      else if (a < 4 || b < 4) pattern = shares(a, b) ? -4.0 : -6.0;
      else pattern = a == b ? 32.0 : shares(a, b) ? 16.0 : 8.0;
      worst = std::max(worst, std::abs(m(a, b) - rho * v / 420.0 * pattern));
    }
  EXPECT_LT(worst, 1e-14 * rho * v);
  EXPECT_NEAR(m.sum(), rho * v, 1e-14 * rho * v);
}

// The gradient of a quadratic field u(x) = c + G x + (xᵀ H_r x)_r sampled at the nodes is reproduced exactly at any
// point of a straight element (what the strains and stresses are made of).
TEST(Tet10Element, QuadraticFieldsAreRepresentedExactly) {
  const fmt10::Tet10Nodes x = straight(some_corners());
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const Eigen::Vector3d c(uniform(random), uniform(random), uniform(random));
  Eigen::Matrix3d g, h[3];
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) {
      g(r, k) = uniform(random);
      for (int l = 0; l < 3; ++l) h[r](k, l) = uniform(random);
    }
  auto u = [&](const Eigen::Vector3d& p) {
    Eigen::Vector3d out = c + g * p;
    for (int r = 0; r < 3; ++r) out(r) += p.dot(h[r] * p);
    return out;
  };
  auto grad_u = [&](const Eigen::Vector3d& p) {  // ∂u_r/∂x_k
    Eigen::Matrix3d out = g;
    for (int r = 0; r < 3; ++r) out.row(r) += (p.transpose() * (h[r] + h[r].transpose()));
    return out;
  };
  Eigen::Matrix<double, 10, 3> nodal;
  for (int a = 0; a < 10; ++a) nodal.row(a) = u(x.row(a).transpose()).transpose();
  double worst = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::Vector3d xi(std::abs(uniform(random)), std::abs(uniform(random)), std::abs(uniform(random)));
    xi /= std::max(1.0, xi.sum() * 1.01);
    const fmt10::Tet10Gradients gr = fmt10::tet10_gradients(x, xi);
    // The physical point of ξ: the element is straight, so x(ξ) is the affine map of the corners.
    const Eigen::Vector3d p = x.row(0).transpose() + (x.topRows<4>().bottomRows<3>().rowwise() - x.row(0)).transpose() * xi;
    const Eigen::Matrix3d recovered = nodal.transpose() * gr.gradients;  // Σ_a u_a ⊗ ∇N_a
    worst = std::max(worst, (recovered - grad_u(p)).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-12);
}

// Rigid motions carry no strain energy, on a curved element too (a mid-edge node moved off its edge's middle).
TEST(Tet10Element, RigidMotionsAreFreeOfStrain) {
  fmt10::Tet10Nodes x = straight(some_corners());
  x.row(6) += Eigen::RowVector3d(0.05, -0.03, 0.08);
  const Eigen::Matrix<double, 30, 30> k = fmt10::tet10_stiffness(x, 1.1e11, 8e10);
  Eigen::Matrix<double, 30, 6> rigid = Eigen::Matrix<double, 30, 6>::Zero();
  for (int a = 0; a < 10; ++a) {
    rigid.block<3, 3>(3 * a, 0).setIdentity();
    const Eigen::Vector3d p = x.row(a).transpose();
    rigid.block<3, 3>(3 * a, 3) << 0, p.z(), -p.y(), -p.z(), 0, p.x(), p.y(), -p.x(), 0;  // ω × p, column k: e_k × p
  }
  EXPECT_LT((k * rigid).cwiseAbs().maxCoeff(), 1e-13 * k.cwiseAbs().maxCoeff() * rigid.cwiseAbs().maxCoeff());
}

// det ∂x/∂ξ is 6V everywhere on a straight element. A mid-edge node moved from its edge's middle toward a corner, past
// the quarter point, folds the element at that corner while every Gauss point stays positive: only the check at the
// nodes sees it. A node pulled beyond the corner folds it at a Gauss point too.
TEST(Tet10Element, JacobianDeterminantsFlagAFoldedElement) {
  const Eigen::Matrix<double, 4, 3> c = some_corners();
  fmt10::Tet10Nodes x = straight(c);
  const Eigen::Matrix<double, 14, 1> good = fmt10::tet10_jacobian_determinants(x);
  EXPECT_LT((good.array() - 6.0 * volume(c)).abs().maxCoeff(), 1e-13 * volume(c));
  x.row(4) = c.row(0) + 0.2 * (c.row(1) - c.row(0));  // the "middle" of edge (0, 1) at a fifth of it
  const Eigen::Matrix<double, 14, 1> folded = fmt10::tet10_jacobian_determinants(x);
  EXPECT_GT(folded.head<4>().minCoeff(), 0.0);  // the Gauss points do not see it
  EXPECT_LE(folded(4), 0.0);                    // corner 0 does
  x.row(4) = c.row(1) + 0.6 * (c.row(1) - c.row(0));  // beyond corner 1
  EXPECT_LE(fmt10::tet10_jacobian_determinants(x).head<4>().minCoeff(), 0.0);
}

// On a curved element (two mid-edge nodes moved off their edges) the mass sums to ρ ∫ det J dξ, the volume computed
// here by an independent 8 x 8 x 8 collapsed Gauss rule from the Jacobian alone (det J is cubic: both rules are exact).
TEST(Tet10Element, CurvedElementMassIsItsVolumeTimesDensity) {
  fmt10::Tet10Nodes x = straight(some_corners());
  x.row(5) += Eigen::RowVector3d(0.08, 0.05, -0.06);
  x.row(9) += Eigen::RowVector3d(-0.04, 0.07, 0.05);
  const double rho = 7850.0;
  // Gauss-Legendre on [0, 1], 8 points, by Newton's iteration on P_8.
  constexpr int n = 8;
  double t[n], w[n];
  for (int i = 0; i < n; ++i) {
    double z = std::cos(3.141592653589793 * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int it = 0; it < 50; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      z -= p1 / dp;
    }
    t[i] = 0.5 * (1.0 + z);
    w[i] = 1.0 / ((1.0 - z * z) * dp * dp);  // 2/((1 − z²) P'²) on [−1, 1], halved
  }
  double volume_curved = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const double u = t[i], v = t[j], s = t[k];
        const Eigen::Vector3d xi(u, v * (1.0 - u), s * (1.0 - u) * (1.0 - v));
        volume_curved += w[i] * w[j] * w[k] * (1.0 - u) * (1.0 - u) * (1.0 - v) * fmt10::tet10_gradients(x, xi).determinant;
      }
  const double mass = fmt10::tet10_mass(x, rho).sum();
  EXPECT_GT(std::abs(volume_curved - volume(some_corners())), 1e-3 * volume_curved);  // it is curved
  EXPECT_NEAR(mass, rho * volume_curved, 1e-13 * rho * volume_curved);
}

// Abaqus 2021's C3D10 matrices of the 4 x 1 x 1 m block (257 nodes, 122 elements; tests/data/abaqus-block). Abaqus
// exported the consistent mass for C3D10 (for C3D4 it exported a lumped one): both agree to round-off, measured
// 1.8e-15 (stiffness) and 2.4e-15 (mass) of the largest entry, which also checks the node order.
TEST(Tet10Element, AbaqusBlockStiffnessAndMass) {
  const auto dir = flexbody::test::data_dir() / "abaqus-block";
  const fp::Tet10Mesh mesh = flexbody::test::read_abaqus_c3d10(dir / "blockC3D10.inp");
  ASSERT_EQ(mesh.tets.rows(), 122);
  const Assembled a = assemble(mesh, kAbaqusSteel);
  const Eigen::Index n = a.stiffness.rows();
  const Eigen::MatrixXd k_abaqus(flexbody::test::read_abaqus_matrix(dir / "blockC3D10_STIF1.mtx", n));
  const Eigen::MatrixXd m_abaqus(flexbody::test::read_abaqus_matrix(dir / "blockC3D10_MASS1.mtx", n));
  const double k_error = (a.stiffness - k_abaqus).cwiseAbs().maxCoeff() / k_abaqus.cwiseAbs().maxCoeff();
  const double m_error = (a.mass - m_abaqus).cwiseAbs().maxCoeff() / m_abaqus.cwiseAbs().maxCoeff();
  std::printf("C3D10 block: stiffness %.3g, mass %.3g (entrywise, relative to the largest entry); mass %.6g kg and "
              "Abaqus' %.6g kg\n", k_error, m_error, a.mass.sum() / 3.0, m_abaqus.sum() / 3.0);
  EXPECT_LT(k_error, 1e-12);
  EXPECT_LT(m_error, 1e-12);
}

// Patch test on the block's mesh: a linear displacement prescribed on its surface nodes is the finite-element
// solution inside (K_ii u_i = −K_ib u_b recovers it), and its gradient, so its strain and stress, is the constant G
// in every element. The bounds leave the solve's rounding (condition of K_ii) room.
TEST(Tet10Element, PatchTestRecoversALinearFieldInside) {
  const auto dir = flexbody::test::data_dir() / "abaqus-block";
  const fp::Tet10Mesh mesh = flexbody::test::read_abaqus_c3d10(dir / "blockC3D10.inp");
  const Assembled a = assemble(mesh, kAbaqusSteel);
  Eigen::Matrix3d g;
  g << 1e-3, 2e-4, -3e-4, 5e-4, -1e-3, 4e-4, -2e-4, 3e-4, 7e-4;
  const Eigen::Vector3d c(1e-3, -2e-3, 5e-4);
  std::vector<Eigen::Index> inside, surface;
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {
    const Eigen::RowVector3d p = mesh.nodes.row(i);
    const bool on = std::abs(p.x()) < 1e-12 || std::abs(p.x() - 4.0) < 1e-12 || std::abs(p.y()) < 1e-12 ||
                    std::abs(p.y() - 1.0) < 1e-12 || std::abs(p.z()) < 1e-12 || std::abs(p.z() - 1.0) < 1e-12;
    for (int r = 0; r < 3; ++r) (on ? surface : inside).push_back(3 * i + r);
  }
  ASSERT_GT(inside.size(), 0u);
  Eigen::VectorXd exact(a.stiffness.rows());
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) exact.segment<3>(3 * i) = c + g * mesh.nodes.row(i).transpose();
  const Eigen::MatrixXd k_ii = a.stiffness(inside, inside), k_ib = a.stiffness(inside, surface);
  const Eigen::VectorXd u_i = k_ii.ldlt().solve(-k_ib * exact(surface));
  const double error = (u_i - exact(inside)).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff();
  Eigen::VectorXd u = exact;
  u(inside) = u_i;
  double strain_error = 0.0;  // ∇u of the solution at each element's centroid against G
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    fmt10::Tet10Nodes x;
    Eigen::Matrix<double, 10, 3> nodal;
    for (int k = 0; k < 10; ++k) {
      x.row(k) = mesh.nodes.row(mesh.tets(e, k));
      nodal.row(k) = u.segment<3>(3 * mesh.tets(e, k)).transpose();
    }
    const fmt10::Tet10Gradients gr = fmt10::tet10_gradients(x, Eigen::Vector3d::Constant(0.25));
    strain_error = std::max(strain_error, (nodal.transpose() * gr.gradients - g).cwiseAbs().maxCoeff());
  }
  std::printf("patch test: %zu interior DOFs, error %.3g of the largest displacement, gradient %.3g of |G|\n",
              inside.size(), error, strain_error / g.cwiseAbs().maxCoeff());
  EXPECT_LT(error, 1e-10);
  EXPECT_LT(strain_error, 1e-9 * g.cwiseAbs().maxCoeff());
}

// The assembly refuses a mesh with a folded element, naming it, rather than assembling a negative volume.
TEST(Tet10Element, AssemblyRefusesAFoldedElement) {
  fp::Tet10Mesh mesh;
  const Eigen::Matrix<double, 4, 3> c = some_corners();
  mesh.nodes = straight(c);
  mesh.tets.resize(1, 10);
  for (int a = 0; a < 10; ++a) mesh.tets(0, a) = a;
  EXPECT_NO_THROW((void)fp::assemble_tet10(mesh, kAbaqusSteel));
  mesh.nodes.row(4) = c.row(0) + 0.2 * (c.row(1) - c.row(0));  // folded at corner 0 only
  try {
    (void)fp::assemble_tet10(mesh, kAbaqusSteel);
    FAIL() << "a folded element was assembled";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("element 0"), std::string::npos) << e.what();
  }
}

// The parallel assembly (element colours, the elements of a colour in parallel, into the node graph's pattern) gives
// the same bits with 1 and 2 threads, and the element matrices' plain sum (triplets, both triangles) to round-off
// (1e-14 of each matrix's norm: the sums differ only in their order).
TEST(Tet10Element, ParallelAssemblyIsTheSumOfTheElementMatrices) {
  const fp::Tet10Mesh mesh = fp::quadratic_mesh(flexbody::test::box_mesh(0.3, 0.05, 0.04, 12, 3, 2));
  const fp::Material steel{"steel", 210e9, 0.3, 7850.0};
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const fp::Tet10Matrices one = fp::assemble_tet10(mesh, steel);
  omp_set_num_threads(std::max(2, threads));
  const fp::Tet10Matrices two = fp::assemble_tet10(mesh, steel);
  omp_set_num_threads(threads);
  ASSERT_EQ(one.stiffness.nonZeros(), two.stiffness.nonZeros());
  EXPECT_TRUE(std::equal(one.stiffness.valuePtr(), one.stiffness.valuePtr() + one.stiffness.nonZeros(),
                         two.stiffness.valuePtr()));
  EXPECT_TRUE(std::equal(one.scalar_mass.valuePtr(), one.scalar_mass.valuePtr() + one.scalar_mass.nonZeros(),
                         two.scalar_mass.valuePtr()));

  std::vector<Eigen::Triplet<double>> k_entries, m_entries;
  const double lambda = fp::lame_lambda(steel), mu = fp::shear_modulus(steel);
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e) {
    fmt10::Tet10Nodes x;
    for (int a = 0; a < 10; ++a) x.row(a) = mesh.nodes.row(mesh.tets(e, a));
    const Eigen::Matrix<double, 30, 30> k = fmt10::tet10_stiffness(x, lambda, mu);
    const Eigen::Matrix<double, 10, 10> m = fmt10::tet10_mass(x, steel.density);
    for (int b = 0; b < 10; ++b)
      for (int a = 0; a < 10; ++a) {
        m_entries.emplace_back(mesh.tets(e, b), mesh.tets(e, a), m(b, a));
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            k_entries.emplace_back(3 * mesh.tets(e, b) + r, 3 * mesh.tets(e, a) + c, k(3 * b + r, 3 * a + c));
      }
  }
  Eigen::SparseMatrix<double> k_sum(mesh.dof_count(), mesh.dof_count()), m_sum(mesh.node_count(), mesh.node_count());
  k_sum.setFromTriplets(k_entries.begin(), k_entries.end());
  m_sum.setFromTriplets(m_entries.begin(), m_entries.end());
  const Eigen::SparseMatrix<double> k_full = fp::full_from_upper(one.stiffness).cast<double>();
  const Eigen::SparseMatrix<double> m_full = fp::full_from_upper(one.scalar_mass).cast<double>();
  EXPECT_LT((k_full - k_sum).norm(), 1e-14 * k_sum.norm());
  EXPECT_LT((m_full - m_sum).norm(), 1e-14 * m_sum.norm());
}
