// The geometric stiffness of unit prestress cases (issue 29, geometric_stiffness.hpp): an exact identity of the
// projection (the virial of the balanced loads), the centrifugal tension of a spinning bar against beam theory, and
// the symmetry and thread-count independence of the result, for linear and quadratic tetrahedra.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/box_mesh.hpp"
#include "flexbody/preprocess/eigensolver.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/geometric_stiffness.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"
#include "flexbody/preprocess/static_correction.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <omp.h>

#include <cstdio>
#include <memory>

namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};
constexpr double kLength = 0.5, kSide = 0.025;  // a slender bar, L/h = 20 (beam theory's tension to ~(h/L)²)

// A free steel bar along x, nodes in its body frame (origin at the centre of mass), with linear or quadratic
// tetrahedra, the relieved static responses of its prestress cases (centrifugal, then a unit fx at each end face)
// and the fields [1, x̄, ȳ, z̄, x̄², x̄ ȳ] the tests project onto.
struct SpunBar {
  int order;
  fp::TetMesh linear;
  std::optional<fp::Tet10Mesh> quadratic;
  fp::RowMatrixX3d nodes;  // body frame
  fp::SparseMatrix stiffness, scalar_mass;
  Eigen::MatrixXd rigid, loads, responses, fields;
  fp::StaticCorrectionStats stats;

  explicit SpunBar(int element_order) : order(element_order) {
    linear = fp::box_mesh(kLength, kSide, kSide, 20, 2, 2);
    linear.nodes.rowwise() -= Eigen::RowVector3d(kLength / 2, kSide / 2, kSide / 2);  // the centre of mass
    if (order == 2) {
      quadratic = fp::quadratic_mesh(linear);
      fp::Tet10Matrices m = fp::assemble_tet10(*quadratic, kSteel);
      stiffness = std::move(m.stiffness);
      scalar_mass = std::move(m.scalar_mass);
      nodes = quadratic->nodes;
    } else {
      const fp::NodeGraph graph = fp::NodeGraph::build(linear);
      const auto geometry = fp::element_geometries(linear);
      stiffness = fp::assemble_stiffness(linear, graph, geometry, kSteel);
      scalar_mass = fp::assemble_scalar_mass(linear, graph, geometry, kSteel.density, fp::MassScheme::consistent);
      nodes = linear.nodes;
    }
    const Eigen::Index n = nodes.rows();
    rigid = fp::rigid_body_modes(nodes, scalar_mass);
    std::vector<fp::LoadPoint> ends = {end_face("root", -kLength / 2), end_face("tip", kLength / 2)};
    const Eigen::MatrixXd interface_loads = fp::unit_load_vectors(nodes, ends);
    loads.resize(3 * n, 6 + interface_loads.cols());
    loads << fp::centrifugal_unit_loads(nodes, scalar_mass), interface_loads;
    const std::unique_ptr<fp::ShiftSolve> solve =
        fp::make_shift_solve(fp::EigensolverBackend::arpack, stiffness, scalar_mass, rigid);
    solve->set_shift(fp::automatic_shift(nodes, kSteel));
    responses = fp::relieved_static_responses(*solve, stiffness, scalar_mass, rigid, loads, stats);
    fields.resize(n, 6);
    fields.col(0).setOnes();
    fields.middleCols(1, 3) = nodes;
    fields.col(4) = nodes.col(0).array().square();
    fields.col(5) = nodes.col(0).cwiseProduct(nodes.col(1));
  }
  fp::LoadPoint end_face(const std::string& name, double x) const {
    std::vector<int> face;
    for (Eigen::Index i = 0; i < nodes.rows(); ++i)
      if (std::abs(nodes(i, 0) - x) < 1e-12) face.push_back(static_cast<int>(i));
    fp::LoadPoint p;
    p.name = name;
    p.nodes = Eigen::Map<const Eigen::VectorXi>(face.data(), static_cast<Eigen::Index>(face.size()));
    p.weights = Eigen::VectorXd::Constant(p.nodes.size(), 1.0 / static_cast<double>(p.nodes.size()));
    p.reference_point = Eigen::Vector3d::Zero();
    for (Eigen::Index a = 0; a < p.nodes.size(); ++a) p.reference_point += p.weights(a) * nodes.row(p.nodes(a)).transpose();
    p.loads = {true, false, false, false, false, false};  // fx only
    return p;
  }
  std::vector<Eigen::MatrixXd> projected() const {
    return quadratic ? fp::projected_geometric_stiffness(*quadratic, kSteel, responses, fields)
                     : fp::projected_geometric_stiffness(linear, kSteel, responses, fields);
  }
  // The load each response balances: f − M̄ R Rᵀ f (R M̄-orthonormal), as the relieved solve projects it.
  Eigen::VectorXd balanced(Eigen::Index k) const {
    Eigen::VectorXd f = loads.col(k), mr(f.size());
    const Eigen::VectorXd r = rigid * (rigid.transpose() * f);
    fp::apply_vector_mass(scalar_mass, r, mr);
    return f - mr;
  }
};

class GeometricStiffness : public ::testing::TestWithParam<int> {};

// For an affine field Y = x̄_i the projection is the virtual work of the displacement x̄_i e_j (in the finite element
// space, integrated as K̄ is): Ĝ(x̄_i, x̄_j) = ∫ σ_ij dV = Σ_nodes x̄_i f_j of the balanced load, exactly up to the
// static solve's residual (1e-10) and round-off. The constant field has no gradient: its row is zero.
TEST_P(GeometricStiffness, TheAffineBlockIsTheVirialOfTheBalancedLoad) {
  const SpunBar bar(GetParam());
  const std::vector<Eigen::MatrixXd> g = bar.projected();
  ASSERT_EQ(g.size(), 8u);  // six centrifugal cases, fx at the root and at the tip
  for (std::size_t k = 0; k < g.size(); ++k) {
    SCOPED_TRACE(k);
    const Eigen::VectorXd f = bar.balanced(static_cast<Eigen::Index>(k));
    Eigen::Matrix3d virial = Eigen::Matrix3d::Zero();
    for (Eigen::Index a = 0; a < bar.nodes.rows(); ++a)
      virial += bar.nodes.row(a).transpose() * f.segment<3>(3 * a).transpose();
    const double scale = g[k].cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    EXPECT_LT((g[k].block<3, 3>(1, 1) - 0.5 * (virial + virial.transpose())).cwiseAbs().maxCoeff(), 1e-8 * scale);
    EXPECT_LT(g[k].row(0).cwiseAbs().maxCoeff(), 1e-9 * scale);
    EXPECT_EQ((g[k] - g[k].transpose()).cwiseAbs().maxCoeff(), 0.0);
  }
  EXPECT_LT(bar.stats.max_relative_residual, 1e-8);
}

// A bar spun about z at Ω carries the tension N(x) = ρ A Ω² (L²/4 − x²)/2 (beam theory, free ends); λ = Ω² on
// centrifugal:zz alone (ω ωᵀ = Ω² e_z e_zᵀ: the force per unit mass (|ω|² I − ω ωᵀ) x̄ = Ω² (x̄, ȳ, 0)). Then for the
// field v = x̄²: Ĝ(v, v) = ∫ N (2 x)² dx = ρ A Ω² L⁵ / 60 per unit Ω², and for v = x̄: ρ A Ω² L³ / 12 (exact: the
// virial above). Measured: quadratic tetrahedra 4.0e-6 off beam theory (the section's lateral stresses), linear ones
// 4.2e-3 (they differentiate x̄² piecewise, 20 cells along); asserted 1e-4 and 1e-2.
TEST_P(GeometricStiffness, ASpunBarCarriesTheBeamTheoryTension) {
  const SpunBar bar(GetParam());
  const std::vector<Eigen::MatrixXd> g = bar.projected();
  const Eigen::MatrixXd& spin_z = g[2];
  const double rho_a = kSteel.density * kSide * kSide;
  std::printf("order %d: G(x, x) / (rho A L^3/12) - 1 = %.2e, G(x^2, x^2) / (rho A L^5/60) - 1 = %.2e, pulled G(x^2, x^2) / "
              "(N L^3/3) - 1 = %.2e\n", GetParam(), spin_z(1, 1) / (rho_a * std::pow(kLength, 3) / 12.0) - 1.0,
              spin_z(4, 4) / (rho_a * std::pow(kLength, 5) / 60.0) - 1.0,
              (g[7] - g[6])(4, 4) / (std::pow(kLength, 3) / 3.0) - 1.0);
  EXPECT_NEAR(spin_z(1, 1) / (rho_a * std::pow(kLength, 3) / 12.0), 1.0, 1e-3);
  const double tolerance = GetParam() == 2 ? 1e-4 : 1e-2;
  EXPECT_NEAR(spin_z(4, 4) / (rho_a * std::pow(kLength, 5) / 60.0), 1.0, tolerance);
  // A spin about y tensions the bar as one about z (the square section); a spin about x (λ on xx) stretches it across,
  // not along: x̄² sees almost nothing of it.
  EXPECT_NEAR(g[1](4, 4) / spin_z(4, 4), 1.0, 1e-6);
  EXPECT_LT(std::abs(g[0](4, 4)), 1e-2 * spin_z(4, 4));
  // Equal and opposite unit forces at the ends pull the bar with 1 N: Ĝ(x̄, x̄) = N L, Ĝ(x̄², x̄²) = N L³/3 (beam theory;
  // the rbe3 loads spread into the section near the ends. Measured: −1.1e-5 quadratic, −2.5e-3 linear).
  const Eigen::MatrixXd pulled = g[7] - g[6];
  EXPECT_NEAR(pulled(1, 1) / kLength, 1.0, 1e-8);
  EXPECT_NEAR(pulled(4, 4) / (std::pow(kLength, 3) / 3.0), 1.0, tolerance);
}

// Cases run on OpenMP's threads, each summed in element order: the same bits on 1 and 2 threads.
TEST_P(GeometricStiffness, IsBitIdenticalForAnyThreadCount) {
  const SpunBar bar(GetParam());
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<Eigen::MatrixXd> one = bar.projected();
  omp_set_num_threads(2);
  const std::vector<Eigen::MatrixXd> two = bar.projected();
  omp_set_num_threads(before);
  for (std::size_t k = 0; k < one.size(); ++k) EXPECT_EQ((one[k] - two[k]).cwiseAbs().maxCoeff(), 0.0) << k;
}

INSTANTIATE_TEST_SUITE_P(Orders, GeometricStiffness, ::testing::Values(1, 2),
                         [](const ::testing::TestParamInfo<int>& order) {
                           return order.param == 1 ? std::string("Linear") : std::string("Quadratic");
                         });

TEST(GeometricStiffnessInput, WrongSizesAreRefused) {
  const fp::TetMesh mesh = fp::box_mesh(1.0, 1.0, 1.0, 1, 1, 1);
  EXPECT_THROW((void)fp::projected_geometric_stiffness(mesh, kSteel, Eigen::MatrixXd::Zero(5, 1),
                                                       Eigen::MatrixXd::Ones(mesh.node_count(), 1)),
               std::invalid_argument);
  Eigen::MatrixXd nan = Eigen::MatrixXd::Zero(3 * mesh.node_count(), 1);
  nan(0, 0) = std::nan("");
  EXPECT_THROW((void)fp::projected_geometric_stiffness(mesh, kSteel, nan, Eigen::MatrixXd::Ones(mesh.node_count(), 1)),
               std::invalid_argument);
}

}  // namespace

// An rbe2 patch held rigid in the static solves (the prestress of a part held at it, issue 29): the spun bar with its
// root face rigid. The response moves that face rigidly (its least-squares rigid fit leaves 1e-12 of the largest
// displacement), stays free of rigid-body motion (Wᵀ M̄ u = 0), and differs from the free bar's, whose face the
// Poisson effect and the end load deform (more than 1e-3 of the largest displacement off rigid); and it is the
// solution of the constrained problem written out densely (1e-8 of the largest displacement).
TEST(GeometricStiffnessRigidPatch, TheHeldFaceMovesRigidly) {
  const SpunBar bar(1);
  const fp::LoadPoint root = bar.end_face("root", -kLength / 2);
  fp::RigidPatches rigid{&bar.nodes, {fp::RigidInterface{root.nodes, root.reference_point}}};
  const std::unique_ptr<fp::ShiftSolve> solve =
      fp::make_shift_solve(fp::EigensolverBackend::arpack, bar.stiffness, bar.scalar_mass, bar.rigid);
  solve->set_shift(fp::automatic_shift(bar.nodes, kSteel));
  fp::StaticCorrectionStats stats;
  const Eigen::MatrixXd held =
      fp::relieved_static_responses(*solve, bar.stiffness, bar.scalar_mass, bar.rigid, bar.loads, stats, {}, "held", rigid);
  // The face's deviation from its least-squares rigid motion, over the largest displacement of the response.
  auto off_rigid = [&](const Eigen::VectorXd& u) {
    Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
    std::vector<Eigen::Matrix<double, 3, 6>> rows;
    for (Eigen::Index a = 0; a < root.nodes.size(); ++a) {
      const Eigen::Vector3d d = bar.nodes.row(root.nodes(a)).transpose() - root.reference_point;
      Eigen::Matrix<double, 3, 6> row;
      row << Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, -d.z(), d.y()), Eigen::Vector3d(d.z(), 0, -d.x()),
          Eigen::Vector3d(-d.y(), d.x(), 0);
      normal += row.transpose() * row;
      rhs += row.transpose() * u.segment<3>(3 * root.nodes(a));
      rows.push_back(row);
    }
    const Eigen::Matrix<double, 6, 1> motion = normal.ldlt().solve(rhs);
    double deviation = 0.0;
    for (Eigen::Index a = 0; a < root.nodes.size(); ++a)
      deviation = std::max(deviation, (rows[static_cast<std::size_t>(a)] * motion - u.segment<3>(3 * root.nodes(a))).norm());
    return deviation / u.cwiseAbs().maxCoeff();
  };
  for (Eigen::Index c = 0; c < bar.loads.cols(); ++c) {
    SCOPED_TRACE(c);
    if (bar.responses.col(c).cwiseAbs().maxCoeff() == 0.0) continue;  // a case the bar's symmetry leaves unloaded
    EXPECT_LT(off_rigid(held.col(c)), 1e-12);
    Eigen::VectorXd m_u(held.rows());
    fp::apply_vector_mass(bar.scalar_mass, held.col(c), m_u);
    EXPECT_LT((bar.rigid.transpose() * m_u).cwiseAbs().maxCoeff(),
              1e-10 * bar.rigid.cwiseAbs().maxCoeff() * m_u.cwiseAbs().sum());
  }
  double largest = 0.0;  // the free bar's root face is not rigid for every case
  for (Eigen::Index c = 0; c < bar.loads.cols(); ++c)
    if (bar.responses.col(c).cwiseAbs().maxCoeff() > 0.0) largest = std::max(largest, off_rigid(bar.responses.col(c)));
  EXPECT_GT(largest, 1e-3);

  // The constrained problem itself, dense and independent of the projected iteration: unknowns u, the face's rigid
  // motion (t, θ), the face's constraint forces λ (u_i = t + θ × d_i) and the relief accelerations a (Wᵀ M̄ u = 0):
  //   K̄ u + Cᵀ λ + M̄ W a = f,  C_mᵀ λ = 0 (the forces on the face balance),  C u + C_m (t, θ) = 0,  Wᵀ M̄ u = 0.
  const Eigen::Index n = bar.stiffness.rows(), k = root.nodes.size(), w = bar.rigid.cols();
  const Eigen::Index size = n + 6 + 3 * k + w;
  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(size, size);
  kkt.topLeftCorner(n, n) = Eigen::MatrixXd(fp::full_from_upper(bar.stiffness));
  Eigen::MatrixXd m_w(n, w);
  for (Eigen::Index c = 0; c < w; ++c) fp::apply_vector_mass(bar.scalar_mass, bar.rigid.col(c), m_w.col(c));
  for (Eigen::Index a = 0; a < k; ++a) {
    const Eigen::Vector3d d = bar.nodes.row(root.nodes(a)).transpose() - root.reference_point;
    Eigen::Matrix<double, 3, 6> master;  // −(t + θ × d)
    master << -Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, d.z(), -d.y()), Eigen::Vector3d(-d.z(), 0, d.x()),
        Eigen::Vector3d(d.y(), -d.x(), 0);
    const Eigen::Index row = n + 6 + 3 * a;
    kkt.block<3, 3>(row, 3 * root.nodes(a)) = Eigen::Matrix3d::Identity();
    kkt.block<3, 3>(3 * root.nodes(a), row) = Eigen::Matrix3d::Identity();
    kkt.block<3, 6>(row, n) = master;
    kkt.block<6, 3>(n, row) = master.transpose();
  }
  kkt.block(0, n + 6 + 3 * k, n, w) = m_w;
  kkt.block(n + 6 + 3 * k, 0, w, n) = m_w.transpose();
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(kkt);
  for (Eigen::Index c = 0; c < bar.loads.cols(); ++c) {
    SCOPED_TRACE(c);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(size);
    rhs.head(n) = bar.loads.col(c);
    const Eigen::VectorXd reference = lu.solve(rhs).head(n);
    if (reference.cwiseAbs().maxCoeff() == 0.0) continue;
    EXPECT_LT((held.col(c) - reference).cwiseAbs().maxCoeff(), 1e-8 * reference.cwiseAbs().maxCoeff());
  }
  // Π is a projector only for disjoint patches: a node in two of them, or on a line of nodes, is refused.
  fp::RigidPatches twice{&bar.nodes, {rigid.patches[0], rigid.patches[0]}};
  EXPECT_THROW((void)fp::relieved_static_responses(*solve, bar.stiffness, bar.scalar_mass, bar.rigid, bar.loads, stats, {},
                                                   "twice", twice),
               std::invalid_argument);
  fp::RigidPatches line{&bar.nodes, {fp::RigidInterface{root.nodes.head(1), root.reference_point}}};
  EXPECT_THROW((void)fp::relieved_static_responses(*solve, bar.stiffness, bar.scalar_mass, bar.rigid, bar.loads, stats, {},
                                                   "line", line),
               std::invalid_argument);
}
