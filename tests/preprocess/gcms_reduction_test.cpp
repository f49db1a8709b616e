// The GCMS constants: G and K̂ against a dense computation, the rotational Tisserand rows against
// nodal sums (Eq. 78), the removal of linearly dependent fields on the square beam (formulations.md, "The Method":
// dependent fields), and prefix truncation.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/gcms_matrices.hpp"
#include "flexbody/preprocess/generalized_fields.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};

struct Reduced {
  flexbody::test::AssembledMesh model;
  fp::FreeFreeModes modes;
  Eigen::MatrixXd upsilon;  // Eq. 49 layout
  fp::GeneralizedFields fields;
};

Reduced reduce(flexbody::test::AssembledMesh model, int mode_count) {
  fp::FreeFreeOptions options;
  options.modes = mode_count;
  Reduced r{std::move(model), {}, {}, {}};
  r.modes = fp::free_free_modes(r.model.mesh.nodes, r.model.stiffness, r.model.scalar_mass, kSteel, options);
  r.upsilon = fp::upsilon_from_modes(r.modes.vectors);
  r.fields = fp::orthonormal_fields(r.model.scalar_mass, r.upsilon);
  return r;
}

// A small bar, nodes moved to the centre of mass (the body frame of Eq. 70).
flexbody::test::AssembledMesh small_bar() {
  auto model = flexbody::test::assemble(flexbody::test::box_mesh(0.3, 0.05, 0.03, 6, 2, 2), kSteel);
  const Eigen::RowVector3d com =
      fp::mass_properties(model.scalar_mass, model.mesh.nodes).center_of_mass_input.transpose();
  model.mesh.nodes.rowwise() -= com;
  return model;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

double max_abs(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

}  // namespace

TEST(GcmsMatrices, EqualADenseComputation) {
  const Reduced r = reduce(small_bar(), 4);
  const Eigen::MatrixXd& u = r.fields.upsilon;
  const Eigen::Index n_n = u.rows(), n_f = u.cols();
  const Eigen::MatrixXd ms = Eigen::MatrixXd(fp::full_from_upper(r.model.scalar_mass));
  const Eigen::MatrixXd k = Eigen::MatrixXd(fp::full_from_upper(r.model.stiffness));
  const Eigen::MatrixXd y = fp::generalized_field_matrix(r.model.mesh.nodes, u);
  const Eigen::MatrixXd g_dense = y.transpose() * ms * y;
  // Ῡ ⊗ I3 formed explicitly (fine at 63 nodes).
  Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(3 * n_n, 3 * n_f);
  for (Eigen::Index i = 0; i < n_n; ++i)
    for (Eigen::Index f = 0; f < n_f; ++f)
      for (int c = 0; c < 3; ++c) phi(3 * i + c, 3 * f + c) = u(i, f);
  const Eigen::MatrixXd k_hat_dense = phi.transpose() * k * phi;
  // K̄ φ cancels heavily for smooth fields, so round-off scales with |Φ|ᵀ|K̄||Φ|, not with K̂ itself.
  const Eigen::MatrixXd k_hat_scale = phi.cwiseAbs().transpose() * k.cwiseAbs() * phi.cwiseAbs();

  const Eigen::MatrixXd g = fp::gcms_mass_matrix(r.model.scalar_mass, r.model.mesh.nodes, u);
  const Eigen::MatrixXd k_hat = fp::reduced_stiffness(r.model.stiffness, u);
  // Sums of a few hundred products: 1e-12 of the sum of their magnitudes is round-off with a wide margin.
  const Eigen::MatrixXd g_scale = y.cwiseAbs().transpose() * ms.cwiseAbs() * y.cwiseAbs();
  EXPECT_LT(((g - g_dense).array() / g_scale.array()).abs().maxCoeff(), 1e-12);
  EXPECT_LT(((k_hat - k_hat_dense).array() / k_hat_scale.array()).abs().maxCoeff(), 1e-12);
  // The blocks formulations.md, "The Method": nodal fields names: mass, zero first moment (centre of mass), Tisserand
  // translation rows zero (modes M-orthogonal to translations), orthonormal fields.
  const double mass = Eigen::VectorXd(r.model.scalar_mass.selfadjointView<Eigen::Upper>() *
                                     Eigen::VectorXd::Ones(n_n)).sum();
  EXPECT_NEAR(g(0, 0), mass, 1e-14 * mass);
  EXPECT_LT(g.block(0, 1, 1, 3).cwiseAbs().maxCoeff(), 1e-14 * mass * 0.3);
  EXPECT_LT(g.block(0, 4, 1, n_f).cwiseAbs().maxCoeff(), 1e-10 * std::sqrt(mass));
  EXPECT_LT(max_abs(g.bottomRightCorner(n_f, n_f) - Eigen::MatrixXd::Identity(n_f, n_f)), 1e-12);
}

TEST(GcmsMatrices, RotationalTisserandRowsAreEq78ByNodalSums) {
  // Eq. 78 in body coordinates: x̃ᵀ M̄ (Ῡ ⊗ I3) ξ̄ = 0, with x̃ the stacked skew matrices of the nodes
  // (Eq. 72). Its 3 x 3 block for field f must be -skew(g_f) with g_f = G[1:4, 4 + f], i.e. the
  // constraint reads sum_f g_f x ξ̄_f = 0.
  const Reduced r = reduce(small_bar(), 4);
  const Eigen::MatrixXd& u = r.fields.upsilon;
  const Eigen::MatrixXd ms = Eigen::MatrixXd(fp::full_from_upper(r.model.scalar_mass));
  const Eigen::MatrixXd g = fp::gcms_mass_matrix(r.model.scalar_mass, r.model.mesh.nodes, u);
  const auto& nodes = r.model.mesh.nodes;
  double worst = 0.0, scale = 0.0;
  for (Eigen::Index f = 0; f < u.cols(); ++f) {
    Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
    for (Eigen::Index i = 0; i < nodes.rows(); ++i)
      for (Eigen::Index j = 0; j < nodes.rows(); ++j)
        if (ms(i, j) != 0.0) block += skew(nodes.row(i).transpose()).transpose() * ms(i, j) * u(j, f);
    const Eigen::Matrix3d from_g = -skew(g.block(1, 4 + f, 3, 1));
    worst = std::max(worst, (block - from_g).cwiseAbs().maxCoeff());
    scale = std::max(scale, block.cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-12 * scale);
}

// Issue 12: G of a 1 mm steel part has second moments of ~1e-17 kg m^2 next to the fields' identity block, so a
// direct eigen solve finds λmin to eps λmax absolute, i.e. not at all. spectral_condition goes through the
// Jacobi scaling and keeps λmin's relative accuracy. A 2 x 2 case with an exact answer: [[a, b], [b, d]] with
// a = 1e-20, d = 1, b = sqrt(a d) / 2 (its Jacobi-scaled form is [[1, 1/2], [1/2, 1]], condition 3).
TEST(GcmsMatrices, SpectralConditionOfAGradedMatrix) {
  const double a = 1e-20, d = 1.0, b = 0.5e-10;
  Eigen::Matrix2d g;
  g << a, b, b, d;
  const double lambda_max = 0.5 * (a + d + std::sqrt((a - d) * (a - d) + 4 * b * b));
  const double lambda_min = (a * d - b * b) / lambda_max;  // the determinant over λmax: no cancellation
  EXPECT_NEAR(fp::spectral_condition(g), lambda_max / lambda_min, 1e-13 * lambda_max / lambda_min);
  EXPECT_NEAR(fp::scaled_condition(g), 3.0, 1e-14 * 3.0);
  // Where the units agree it is the plain λmax / λmin (a small well-conditioned SPD matrix).
  Eigen::Matrix3d c;
  c << 4, 1, 0.5, 1, 3, 0.25, 0.5, 0.25, 2;
  const Eigen::Vector3d values = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c).eigenvalues();
  EXPECT_NEAR(fp::spectral_condition(c), values(2) / values(0), 1e-14 * values(2) / values(0));
  // Not positive definite: +inf, as before.
  Eigen::Matrix2d indefinite;
  indefinite << 1e-20, 1.5e-10, 1.5e-10, 1;
  EXPECT_TRUE(std::isinf(fp::spectral_condition(indefinite)));
  EXPECT_TRUE(std::isinf(fp::scaled_condition(indefinite)));
}

TEST(GeneralizedFields, SquareBeamDependencyIsRemoved) {
  // The must-pass case of formulations.md, "The Method": dependent fields: the square beam's bending pairs make the
  // fields nearly dependent, and the cross-components of each mode are decades smaller than its main one.
  const Reduced r = reduce(flexbody::test::square_beam(), 8);
  const Eigen::MatrixXd& ups = r.upsilon;
  const auto& ms = r.model.scalar_mass;
  const Eigen::MatrixXd gram_before = ups.transpose() * (ms.selfadjointView<Eigen::Upper>() * ups);
  const double cond_before = fp::spectral_condition(gram_before);
  const Eigen::MatrixXd& u = r.fields.upsilon;
  const Eigen::MatrixXd gram_after = u.transpose() * (ms.selfadjointView<Eigen::Upper>() * u);
  // Measured: 2.5e7 before. No field is dependent to round-off on this unstructured mesh (the smallest
  // remainder is 8e-4 of its mode), so all 24 are kept: the disparity of scales was the problem, and
  // M_s-orthonormal fields remove it without changing the span.
  EXPECT_GT(cond_before, 1e6);
  EXPECT_EQ(r.fields.dropped, 0);
  const Eigen::MatrixXd g_before = fp::gcms_mass_matrix(ms, r.model.mesh.nodes, ups);
  const Eigen::MatrixXd g_after = fp::gcms_mass_matrix(ms, r.model.mesh.nodes, u);
  // G improves with it (measured 2.9e8 before, 5.9e5 after; what is left is the fields' overlap with the
  // rotations X̄, which the rotational Tisserand constraint handles, and the units of G's blocks).
  EXPECT_LT(fp::spectral_condition(g_after), 1e-2 * fp::spectral_condition(g_before));
  EXPECT_LT(max_abs(gram_after - Eigen::MatrixXd::Identity(u.cols(), u.cols())), 1e-12);
  // Nothing of the modes is lost: each field is reproduced by the kept ones up to the drop tolerance.
  const Eigen::MatrixXd lost = ups - u * r.fields.mode_coefficients;
  const Eigen::MatrixXd lost_gram = lost.transpose() * (ms.selfadjointView<Eigen::Upper>() * lost);
  EXPECT_LT(std::sqrt(lost_gram.diagonal().maxCoeff()), 1e-8);
  // The reduced linear model K̂ x = λ x (G_ff = I) still holds every free-free frequency.
  const Eigen::MatrixXd k_hat = fp::reduced_stiffness(r.model.stiffness, u);
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(k_hat).eigenvalues();
  for (Eigen::Index m = 0; m < r.modes.eigenvalues.size(); ++m) {
    const double target = r.modes.eigenvalues(m);
    EXPECT_LT((lambda.array() - target).abs().minCoeff(), 1e-8 * target) << "mode " << m;
  }
}

TEST(GeneralizedFields, ExactlyDependentFieldsAreDroppedAndStillRepresented) {
  // A fifth "mode" made of the first mode's fields in another order (z, x, y): its three fields are
  // copies of kept ones, so all three must go, and C must give them back from the kept fields.
  const Reduced r = reduce(small_bar(), 4);
  Eigen::MatrixXd ups(r.upsilon.rows(), 15);
  ups << r.upsilon, r.upsilon.col(2), r.upsilon.col(0), r.upsilon.col(1);
  const fp::GeneralizedFields fields = fp::orthonormal_fields(r.model.scalar_mass, ups);
  EXPECT_EQ(fields.dropped, 3);
  EXPECT_EQ(fields.upsilon.cols(), 12);
  EXPECT_EQ(fields.upsilon, r.fields.upsilon);  // the first four modes decide alone
  EXPECT_LT(fields.relative_remainders.tail(3).maxCoeff(), 1e-13);  // copies: round-off only
  EXPECT_GT(fields.relative_remainders.head(12).minCoeff(), 1e-8);
  const Eigen::MatrixXd lost = ups - fields.upsilon * fields.mode_coefficients;
  EXPECT_LT(lost.cwiseAbs().maxCoeff(), 1e-12 * ups.cwiseAbs().maxCoeff());
}

TEST(GeneralizedFields, NearlyDependentFieldsStayOrthonormal) {
  // A fifth "mode": the first mode's fields plus 1e-6 of the fields x², y², z² (M_s-normalised), which
  // the modes do not span: remainders of about 1e-6, kept (above 1e-8) yet nearly dependent. One
  // Gram-Schmidt pass with updated products would leave round-off of the removed part, eps / 1e-6 ~ 1e-10,
  // in the orthonormality; recomputed products and the second pass keep it at working precision.
  const Reduced r = reduce(small_bar(), 4);
  const auto& ms = r.model.scalar_mass;
  Eigen::MatrixXd squares = r.model.mesh.nodes.array().square().matrix();
  for (int c = 0; c < 3; ++c) {
    const Eigen::VectorXd m_col = ms.selfadjointView<Eigen::Upper>() * squares.col(c);
    squares.col(c) /= std::sqrt(squares.col(c).dot(m_col));
  }
  Eigen::MatrixXd ups(r.upsilon.rows(), 15);
  ups << r.upsilon, r.upsilon.leftCols(3) + 1e-6 * squares;
  const fp::GeneralizedFields fields = fp::orthonormal_fields(ms, ups);
  EXPECT_GT(fields.relative_remainders.tail(3).minCoeff(), 1e-8);  // near, not exact: kept
  EXPECT_LT(fields.relative_remainders.tail(3).maxCoeff(), 1e-5);
  const Eigen::Index n_f = fields.upsilon.cols();
  const Eigen::MatrixXd gram = fields.upsilon.transpose() * (ms.selfadjointView<Eigen::Upper>() * fields.upsilon);
  EXPECT_LT(max_abs(gram - Eigen::MatrixXd::Identity(n_f, n_f)), 1e-12);
}

TEST(GeneralizedFields, APrefixOfModesGivesThePrefixOfFieldsAndBlocks) {
  const Reduced all = reduce(flexbody::test::square_beam(), 8);
  const fp::GeneralizedFields first = fp::orthonormal_fields(all.model.scalar_mass, all.upsilon.leftCols(3 * 5));
  const Eigen::Index n_f = first.upsilon.cols();
  ASSERT_EQ(n_f, (all.fields.source_mode.array() < 5).count());
  EXPECT_EQ(first.upsilon, all.fields.upsilon.leftCols(n_f));  // same arithmetic: bit for bit
  const auto& model = all.model;
  const Eigen::MatrixXd g_all = fp::gcms_mass_matrix(model.scalar_mass, model.mesh.nodes, all.fields.upsilon);
  const Eigen::MatrixXd g_first = fp::gcms_mass_matrix(model.scalar_mass, model.mesh.nodes, first.upsilon);
  const Eigen::MatrixXd k_all = fp::reduced_stiffness(model.stiffness, all.fields.upsilon);
  const Eigen::MatrixXd k_first = fp::reduced_stiffness(model.stiffness, first.upsilon);
  // Equal up to the summation order inside the matrix products (blocking): 1e-14 of the largest entry.
  EXPECT_LT(max_abs(g_first - g_all.topLeftCorner(4 + n_f, 4 + n_f)), 1e-14 * max_abs(g_all));
  EXPECT_LT(max_abs(k_first - k_all.topLeftCorner(3 * n_f, 3 * n_f)), 1e-14 * max_abs(k_all));
}
