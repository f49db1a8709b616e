// Stress recovery of linear tetrahedra: the patch test (linear fields give their exact uniform stress at every
// node), stress-free rigid rotations, volume-weighted nodal averaging checked against element stresses computed
// by hand, the stress modes of scalar fields against the analytic stresses and against nodal_stresses, regions,
// thread-count independence, von Mises by hand, and every refused input. Quadratic tetrahedra (issue 15): the
// quadratic patch test, linear fields on curved elements, stress modes against nodal_stresses.
#include "flexbody/preprocess/stress_recovery.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"
#include "flexbody/preprocess/tet4_element.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace fp = flexbody::preprocess;

namespace {

using Voigt = Eigen::Matrix<double, 6, 1>;

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};

// σ = λ tr(ε) I + 2 μ ε of the displacement gradient h(r, c) = ∂u_r/∂x_c, Voigt order xx yy zz xy xz yz.
Voigt hooke(const Eigen::Matrix3d& h, const fp::Material& material) {
  const double lambda = fp::lame_lambda(material), mu = fp::shear_modulus(material);
  const Eigen::Matrix3d strain = 0.5 * (h + h.transpose());
  const Eigen::Matrix3d s = lambda * strain.trace() * Eigen::Matrix3d::Identity() + 2.0 * mu * strain;
  Voigt v;
  v << s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(0, 2), s(1, 2);
  return v;
}

Eigen::MatrixXd random_matrix(Eigen::Index rows, Eigen::Index cols, double scale, std::mt19937& rng) {
  std::uniform_real_distribution<double> uniform(-scale, scale);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index c = 0; c < cols; ++c)
    for (Eigen::Index r = 0; r < rows; ++r) m(r, c) = uniform(rng);
  return m;
}

// The node-interleaved displacement u_i = H x_i + b of every node (one column).
Eigen::MatrixXd affine_displacement(const fp::TetMesh& mesh, const Eigen::Matrix3d& h, const Eigen::Vector3d& b) {
  Eigen::MatrixXd u(mesh.dof_count(), 1);
  for (Eigen::Index i = 0; i < mesh.node_count(); ++i) u.col(0).segment<3>(3 * i) = h * mesh.nodes.row(i).transpose() + b;
  return u;
}

// Largest |stress - expected| over every node of one column of a 6 n_n result.
double worst_deviation(const Eigen::MatrixXd& stresses, Eigen::Index column, const Voigt& expected) {
  double worst = 0.0;
  for (Eigen::Index i = 0; i < stresses.rows() / 6; ++i)
    worst = std::max(worst, (stresses.col(column).segment<6>(6 * i) - expected).cwiseAbs().maxCoeff());
  return worst;
}

// A 3 x 3 x 3-cell box with its interior nodes moved by up to 0.3 cell: irregular, still positively oriented.
fp::TetMesh irregular_box() {
  fp::TetMesh mesh = flexbody::test::box_mesh(0.3, 0.2, 0.1, 3, 3, 3);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const Eigen::Vector3d cell(0.1, 0.2 / 3, 0.1 / 3), size(0.3, 0.2, 0.1);
  for (Eigen::Index i = 0; i < mesh.node_count(); ++i) {
    bool interior = true;
    for (int k = 0; k < 3; ++k) interior = interior && mesh.nodes(i, k) > 1e-9 && mesh.nodes(i, k) < size(k) - 1e-9;
    if (interior)
      for (int k = 0; k < 3; ++k) mesh.nodes(i, k) += jitter(rng) * cell(k);
  }
  for (Eigen::Index e = 0; e < mesh.element_count(); ++e)
    EXPECT_GT(fp::tet4_geometry(fp::element_corners(mesh, e)).volume, 0.0) << "element " << e;
  return mesh;
}

template <typename Call>
void expect_refused(Call&& call, const std::string& message) {
  SCOPED_TRACE(message);
  try {
    (void)call();
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(StressRecovery, PatchTestGivesTheExactUniformStressAtEveryNode) {
  // Constant-strain elements reproduce a linear displacement exactly: Σ_a x_a ⊗ ∇N_a = I and Σ_a ∇N_a = 0 in each
  // element, so every element (and every volume average) has the gradient H, and the stress is the uniform
  // hooke(H) everywhere, boundary nodes included. What remains is rounding: a gradient sums ~15 neighbour terms of
  // size |u| / h with |u| <= |H| L + |b|, L / h ≈ 50 on the beam, so about 15 · 50 · 1e-16 ≈ 1e-13 of the stress
  // (measured 3e-14 with gcc 12).
  const fp::TetMesh& mesh = flexbody::test::square_beam().mesh;
  std::mt19937 rng(1);
  const Eigen::Matrix3d h = random_matrix(3, 3, 1e-3, rng);
  const Eigen::Vector3d b = random_matrix(3, 1, 1e-3, rng);
  const Eigen::MatrixXd stresses = fp::nodal_stresses(mesh, kSteel, affine_displacement(mesh, h, b));
  ASSERT_EQ(stresses.rows(), 6 * mesh.node_count());
  ASSERT_EQ(stresses.cols(), 1);
  const Voigt expected = hooke(h, kSteel);
  EXPECT_LT(worst_deviation(stresses, 0, expected), 1e-12 * expected.cwiseAbs().maxCoeff());
}

TEST(StressRecovery, RigidRotationIsStressFree) {
  // u = ω × x + b has the skew gradient [ω]×, zero strain. Rounding as in the patch test: ~15 terms of size
  // |u| / h with |u| <= |ω| L / 2 + |b| ≈ 5e-4 m here and h ≈ 0.02 m, i.e. ~40 |ω|, so ~15 · 40 · 1e-16 ≈ 6e-14 of
  // E |ω| (the stress a strain of |ω| would give; measured 1.6e-14 with gcc 12).
  const fp::TetMesh& mesh = flexbody::test::square_beam().mesh;
  const Eigen::Vector3d omega(2e-4, -3e-4, 5e-4), b(1e-4, 2e-4, -1e-4);
  Eigen::Matrix3d skew;
  skew << 0, -omega.z(), omega.y(), omega.z(), 0, -omega.x(), -omega.y(), omega.x(), 0;
  const Eigen::MatrixXd stresses = fp::nodal_stresses(mesh, kSteel, affine_displacement(mesh, skew, b));
  EXPECT_LT(stresses.cwiseAbs().maxCoeff(), 1e-12 * kSteel.youngs_modulus * omega.norm());
}

TEST(StressRecovery, AveragesElementStressesByVolume) {
  // Two tetrahedra of different volumes sharing the face (0, 1, 2), and a random (non-linear) displacement: the
  // element stresses differ, so the shared nodes see their volume-weighted mean, the tips their own element's.
  // Reference: element stresses from the element gradients directly (H = Σ_a u_a ∇N_aᵀ); both routes differ by
  // rounding only (sums of 4-8 terms: 1e-12 of the largest stress is ample).
  fp::TetMesh mesh;
  mesh.nodes.resize(5, 3);
  mesh.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.3, 0.5, 0.3, 0.1, -1.7;
  mesh.tets.resize(2, 4);
  mesh.tets << 0, 1, 2, 3, 0, 2, 1, 4;
  std::mt19937 rng(3);
  const Eigen::MatrixXd u = random_matrix(15, 2, 1e-3, rng);
  const Eigen::MatrixXd stresses = fp::nodal_stresses(mesh, kSteel, u);
  for (Eigen::Index column = 0; column < 2; ++column) {
    Voigt element_stress[2];
    double volume[2];
    for (int e = 0; e < 2; ++e) {
      const fp::Tet4Geometry g = fp::tet4_geometry(fp::element_corners(mesh, e));
      ASSERT_GT(g.volume, 0.0);
      Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
      for (int a = 0; a < 4; ++a) h += u.col(column).segment<3>(3 * mesh.tets(e, a)) * g.gradients.row(a);
      element_stress[e] = hooke(h, kSteel);
      volume[e] = g.volume;
    }
    EXPECT_GT(volume[1], 3.0 * volume[0]);  // the weights matter
    const Voigt shared = (volume[0] * element_stress[0] + volume[1] * element_stress[1]) / (volume[0] + volume[1]);
    const Voigt expected[5] = {shared, shared, shared, element_stress[0], element_stress[1]};
    const double scale = std::max(element_stress[0].cwiseAbs().maxCoeff(), element_stress[1].cwiseAbs().maxCoeff());
    for (int i = 0; i < 5; ++i)
      EXPECT_LT((stresses.col(column).segment<6>(6 * i) - expected[i]).cwiseAbs().maxCoeff(), 1e-12 * scale)
          << "node " << i << ", column " << column;
  }
}

TEST(StressRecovery, StressModesOfLinearAndRandomFields) {
  const fp::TetMesh& mesh = flexbody::test::square_beam().mesh;
  const Eigen::Index n = mesh.node_count();
  std::mt19937 rng(5);
  Eigen::MatrixXd fields(n, 4);
  fields.leftCols<3>() = mesh.nodes;
  fields.col(3) = random_matrix(n, 1, 1.0, rng);
  const Eigen::VectorXi all = Eigen::VectorXi::LinSpaced(n, 0, static_cast<int>(n) - 1);
  const Eigen::MatrixXd modes = fp::nodal_stress_modes(mesh, kSteel, fields, all);
  ASSERT_EQ(modes.rows(), 6 * n);
  ASSERT_EQ(modes.cols(), 12);

  // Field x_f along e_d: H = e_d e_fᵀ, uniform stress λ δ_fd I + μ (e_d e_fᵀ + e_f e_dᵀ); exact up to rounding
  // (patch test argument, |u| / h ≈ L / h ≈ 50).
  for (int f = 0; f < 3; ++f)
    for (int d = 0; d < 3; ++d) {
      Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
      h(d, f) = 1.0;
      const Voigt expected = hooke(h, kSteel);
      EXPECT_LT(worst_deviation(modes, 3 * f + d, expected), 1e-12 * expected.cwiseAbs().maxCoeff())
          << "field " << f << ", direction " << d;
    }

  // The random field along e_d is the vector field whose d-components are the field: nodal_stresses of it. Same
  // operators, different bookkeeping: equal up to rounding of the largest stress (bit for bit with gcc 12, since
  // nodal_stress_modes evaluates every entry the way nodal_stresses does).
  Eigen::MatrixXd vector_fields = Eigen::MatrixXd::Zero(3 * n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) vector_fields(3 * i + d, d) = fields(i, 3);
  const Eigen::MatrixXd reference = fp::nodal_stresses(mesh, kSteel, vector_fields);
  for (int d = 0; d < 3; ++d)
    EXPECT_LT((modes.col(9 + d) - reference.col(d)).cwiseAbs().maxCoeff(),
              1e-12 * reference.col(d).cwiseAbs().maxCoeff())
        << "direction " << d;

  // A region (any order, a repeat) gets exactly the rows of its nodes: each node's result depends on nothing else.
  const Eigen::VectorXi region = (Eigen::VectorXi(6) << 17, 3, static_cast<int>(n) - 1, 0, 17, static_cast<int>(n) / 2).finished();
  const Eigen::MatrixXd part = fp::nodal_stress_modes(mesh, kSteel, fields, region);
  ASSERT_EQ(part.rows(), 6 * region.size());
  ASSERT_EQ(part.cols(), 12);
  for (Eigen::Index j = 0; j < region.size(); ++j)
    EXPECT_TRUE((part.middleRows<6>(6 * j).array() == modes.middleRows<6>(6 * region(j)).array()).all()) << j;
}

TEST(StressRecovery, ResultsDoNotDependOnTheThreadCount) {
  // More than one chunk of output nodes (the beam has ~700), so several threads really share the work.
  const fp::TetMesh& mesh = flexbody::test::square_beam().mesh;
  std::mt19937 rng(9);
  const Eigen::MatrixXd u = random_matrix(mesh.dof_count(), 3, 1e-3, rng);
  const Eigen::MatrixXd fields = random_matrix(mesh.node_count(), 3, 1.0, rng);
  const Eigen::VectorXi all = Eigen::VectorXi::LinSpaced(mesh.node_count(), 0, static_cast<int>(mesh.node_count()) - 1);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Eigen::MatrixXd serial = fp::nodal_stresses(mesh, kSteel, u);
  const Eigen::MatrixXd serial_modes = fp::nodal_stress_modes(mesh, kSteel, fields, all);
  omp_set_num_threads(std::max(2, threads));
  const Eigen::MatrixXd parallel = fp::nodal_stresses(mesh, kSteel, u);
  const Eigen::MatrixXd parallel_modes = fp::nodal_stress_modes(mesh, kSteel, fields, all);
  omp_set_num_threads(threads);
  EXPECT_TRUE((serial.array() == parallel.array()).all());
  EXPECT_TRUE((serial_modes.array() == parallel_modes.array()).all());
  // Columns are independent: one column alone gives the same bits.
  EXPECT_TRUE((fp::nodal_stresses(mesh, kSteel, u.col(1)).array() == serial.col(1).array()).all());
}

TEST(StressRecovery, VonMisesOfHandValues) {
  // sqrt(x²) and sqrt(3 τ²) vs √3 τ: correctly rounded operations, equal to a few ulps (EXPECT_DOUBLE_EQ: 4 ulps).
  const double s = 123.4e6, tau = 56.7e6;
  EXPECT_DOUBLE_EQ(fp::von_mises((Voigt() << s, 0, 0, 0, 0, 0).finished()), s);
  EXPECT_DOUBLE_EQ(fp::von_mises((Voigt() << 0, 0, -s, 0, 0, 0).finished()), s);
  EXPECT_DOUBLE_EQ(fp::von_mises((Voigt() << 0, 0, 0, tau, 0, 0).finished()), std::sqrt(3.0) * tau);
  EXPECT_DOUBLE_EQ(fp::von_mises((Voigt() << 0, 0, 0, 0, 0, -tau).finished()), std::sqrt(3.0) * tau);
  EXPECT_EQ(fp::von_mises((Voigt() << s, s, s, 0, 0, 0).finished()), 0.0);  // hydrostatic: exactly zero
  // A general tensor against its principal stresses (rotation invariance); the eigensolver is accurate to ~1e-15
  // of the largest stress, so 1e-13 relative.
  Voigt v;
  v << 80e6, -20e6, 35e6, 12e6, -40e6, 25e6;
  Eigen::Matrix3d t;
  t << v(0), v(3), v(4), v(3), v(1), v(5), v(4), v(5), v(2);
  const Eigen::Vector3d p = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(t).eigenvalues();
  const double principal =
      std::sqrt(0.5 * ((p(0) - p(1)) * (p(0) - p(1)) + (p(1) - p(2)) * (p(1) - p(2)) + (p(2) - p(0)) * (p(2) - p(0))));
  EXPECT_NEAR(fp::von_mises(v), principal, 1e-13 * principal);
}

TEST(StressRecovery, RefusesBadInput) {
  const fp::TetMesh mesh = irregular_box();
  const Eigen::Index n = mesh.node_count();
  const Eigen::MatrixXd u = Eigen::MatrixXd::Zero(3 * n, 2);
  const Eigen::MatrixXd fields = Eigen::MatrixXd::Zero(n, 2);
  const Eigen::VectorXi region = (Eigen::VectorXi(2) << 0, 5).finished();
  auto stresses = [&](const fp::TetMesh& m, const fp::Material& material, const Eigen::MatrixXd& d) {
    return fp::nodal_stresses(m, material, d);
  };
  auto modes = [&](const fp::TetMesh& m, const Eigen::MatrixXd& f, const Eigen::VectorXi& nodes) {
    return fp::nodal_stress_modes(m, kSteel, f, nodes);
  };
  // Sanity: the good inputs pass.
  EXPECT_NO_THROW((void)stresses(mesh, kSteel, u));
  EXPECT_NO_THROW((void)modes(mesh, fields, region));

  expect_refused([&] { return stresses(mesh, kSteel, Eigen::MatrixXd::Zero(3 * n - 1, 1)); },
                 fmt::format("displacements has {} rows, expected 3 n_n = {}", 3 * n - 1, 3 * n));
  expect_refused([&] { return modes(mesh, Eigen::MatrixXd::Zero(n + 1, 1), region); },
                 fmt::format("fields has {} rows, expected one per node ({})", n + 1, n));
  expect_refused([&] { return modes(mesh, fields, (Eigen::VectorXi(2) << 0, static_cast<int>(n)).finished()); },
                 fmt::format("region node {} (entry 1) is out of range", n));
  expect_refused([&] { return modes(mesh, fields, (Eigen::VectorXi(1) << -1).finished()); },
                 "region node -1 (entry 0) is out of range");
  Eigen::MatrixXd bad_u = u;
  bad_u(7, 1) = std::numeric_limits<double>::quiet_NaN();
  expect_refused([&] { return stresses(mesh, kSteel, bad_u); }, "displacements(7, 1) is nan");
  Eigen::MatrixXd bad_fields = fields;
  bad_fields(4, 0) = std::numeric_limits<double>::infinity();
  expect_refused([&] { return modes(mesh, bad_fields, region); }, "fields(4, 0) is inf");

  fp::TetMesh bad_mesh = mesh;
  bad_mesh.tets(2, 3) = static_cast<std::int32_t>(n);
  expect_refused([&] { return stresses(bad_mesh, kSteel, u); },
                 fmt::format("tetrahedron 2 refers to node {}, the mesh has {} nodes", n, n));
  bad_mesh = mesh;
  bad_mesh.nodes(3, 1) = std::numeric_limits<double>::quiet_NaN();
  expect_refused([&] { return modes(bad_mesh, fields, region); }, "mesh node 3 has a non-finite coordinate");
  bad_mesh = mesh;
  std::swap(bad_mesh.tets(4, 0), bad_mesh.tets(4, 1));  // inverted
  expect_refused([&] { return stresses(bad_mesh, kSteel, u); }, "tetrahedron 4 has volume -");
  bad_mesh = mesh;
  bad_mesh.nodes.conservativeResize(n + 1, 3);
  bad_mesh.nodes.row(n) << 1.0, 1.0, 1.0;  // a node in no element: no stress to average
  expect_refused([&] { return stresses(bad_mesh, kSteel, Eigen::MatrixXd::Zero(3 * n + 3, 1)); },
                 fmt::format("node {} belongs to no element", n));
  expect_refused([&] { return stresses(mesh, fp::Material{"bad", 210e9, 0.5, 7850.0}, u); }, "nu must lie in");
}

// Quadratic tetrahedra. A quadratic displacement u_r(x) = (H x)_r + ½ xᵀ Q_r x has the linear gradient
// ∂u_r/∂x_c = H_rc + (Q_r x)_c, which a straight-sided 10-node element holds exactly; its stress at each node,
// extrapolated from the 4 Gauss points (linear there too), is exact, so every node's volume average is
// hooke(∇u(x_i)). Rounding only: 1e-10 of the largest stress (measured 3e-15). Evaluating the element's stress at its
// Gauss points without the extrapolation misses by the stress's change between the node and its Gauss point (checked:
// 7.4e7 of 1.24e9 Pa here).
TEST(StressRecovery, QuadraticTetrahedraRecoverTheExactStressOfAQuadraticField) {
  const fp::Tet10Mesh mesh = fp::quadratic_mesh(irregular_box());
  std::mt19937 rng(11);
  const Eigen::Matrix3d h = random_matrix(3, 3, 1e-3, rng);
  Eigen::Matrix3d q[3];
  for (auto& qr : q) {
    qr = random_matrix(3, 3, 1e-2, rng);
    qr = (0.5 * (qr + qr.transpose())).eval();
  }
  auto gradient = [&](const Eigen::Vector3d& x) {
    Eigen::Matrix3d g = h;
    for (int r = 0; r < 3; ++r) g.row(r) += (q[r] * x).transpose();
    return g;
  };
  Eigen::MatrixXd u(mesh.dof_count(), 1);
  for (Eigen::Index i = 0; i < mesh.node_count(); ++i) {
    const Eigen::Vector3d x = mesh.nodes.row(i).transpose();
    for (int r = 0; r < 3; ++r) u(3 * i + r, 0) = h.row(r).dot(x) + 0.5 * x.dot(q[r] * x);
  }
  const Eigen::MatrixXd stresses = fp::nodal_stresses(mesh, kSteel, u);
  double worst = 0.0, largest = 0.0;
  for (Eigen::Index i = 0; i < mesh.node_count(); ++i) {
    const Voigt expected = hooke(gradient(mesh.nodes.row(i).transpose()), kSteel);
    worst = std::max(worst, (stresses.col(0).segment<6>(6 * i) - expected).cwiseAbs().maxCoeff());
    largest = std::max(largest, expected.cwiseAbs().maxCoeff());
  }
  std::printf("quadratic field on %ld quadratic tetrahedra: worst nodal stress error %.3g of %.3g Pa\n",
              static_cast<long>(mesh.element_count()), worst, largest);
  EXPECT_LT(worst, 1e-10 * largest);
}

// Curved elements (interior mid-edge nodes moved off their edges' middles by up to 15 % of the cell) still represent a
// linear displacement exactly (isoparametric), and the extrapolation reproduces a constant stress (its rows sum to
// 1): the patch test of the curved mesh. Also: the stress modes of scalar fields equal nodal_stresses of those fields
// along x, y, z (to rounding, 1e-12: the two sum the same terms in different orders), and a folded element around an
// output node is refused.
TEST(StressRecovery, CurvedQuadraticTetrahedraPassThePatchTest) {
  fp::Tet10Mesh mesh = fp::quadratic_mesh(flexbody::test::box_mesh(0.3, 0.2, 0.1, 3, 3, 3));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15);
  const Eigen::Vector3d cell(0.1, 0.2 / 3, 0.1 / 3), size(0.3, 0.2, 0.1);
  const Eigen::Index corners = flexbody::test::box_mesh(0.3, 0.2, 0.1, 3, 3, 3).node_count();
  for (Eigen::Index i = corners; i < mesh.node_count(); ++i) {
    bool interior = true;
    for (int k = 0; k < 3; ++k) interior = interior && mesh.nodes(i, k) > 1e-9 && mesh.nodes(i, k) < size(k) - 1e-9;
    if (interior)
      for (int k = 0; k < 3; ++k) mesh.nodes(i, k) += jitter(rng) * cell(k);
  }
  const Eigen::Matrix3d h = random_matrix(3, 3, 1e-3, rng);
  Eigen::MatrixXd u(mesh.dof_count(), 1);
  for (Eigen::Index i = 0; i < mesh.node_count(); ++i) u.col(0).segment<3>(3 * i) = h * mesh.nodes.row(i).transpose();
  const Eigen::MatrixXd stresses = fp::nodal_stresses(mesh, kSteel, u);
  const Voigt expected = hooke(h, kSteel);
  EXPECT_LT(worst_deviation(stresses, 0, expected), 1e-10 * expected.cwiseAbs().maxCoeff());

  const Eigen::MatrixXd fields = random_matrix(mesh.node_count(), 2, 1.0, rng);
  const Eigen::VectorXi region = Eigen::VectorXi::LinSpaced(mesh.node_count(), 0, static_cast<int>(mesh.node_count()) - 1);
  const Eigen::MatrixXd modes = fp::nodal_stress_modes(mesh, kSteel, fields, region);
  for (Eigen::Index f = 0; f < 2; ++f)
    for (int d = 0; d < 3; ++d) {
      Eigen::MatrixXd along = Eigen::MatrixXd::Zero(mesh.dof_count(), 1);
      for (Eigen::Index i = 0; i < mesh.node_count(); ++i) along(3 * i + d, 0) = fields(i, f);
      EXPECT_LT((modes.col(3 * f + d) - fp::nodal_stresses(mesh, kSteel, along).col(0)).cwiseAbs().maxCoeff(),
                1e-12 * modes.col(3 * f + d).cwiseAbs().maxCoeff());
    }

  mesh.nodes.row(mesh.tets(0, 4)) = mesh.nodes.row(mesh.tets(0, 2));  // edge (0,1)'s middle onto corner 2: folded
  expect_refused([&] { (void)fp::nodal_stresses(mesh, kSteel, u); }, "quadratic tetrahedron 0 is inverted or folded");
}
