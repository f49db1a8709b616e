// Loading a body: all modes, the first k (prefix slicing of every block), or rigid.
#include "flexbody/runtime/body_model.hpp"
#include "flexbody/runtime/system.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <limits>
#include <string>

namespace fr = flexbody::runtime;
namespace ff = flexbody::format;

namespace {

// Three modes with 3, 2 and 1 fields (field_mode 0 0 0 1 1 2), one interface, one output region, on 4 nodes.
ff::BodyData synthetic_body() {
  ff::BodyData body;
  body.mass.mass = 2.5;
  body.mesh.nodes = ff::RowMatrixX3d::Random(4, 3);
  body.modes.frequencies_hz = Eigen::Vector3d(10.0, 20.0, 30.0);
  const Eigen::Index n_f = 6;
  body.gcms.field_mode.resize(n_f);
  body.gcms.field_mode << 0, 0, 0, 1, 1, 2;
  body.gcms.fields = Eigen::MatrixXd::Random(4, n_f);
  body.gcms.mass_matrix = Eigen::MatrixXd::Random(4 + n_f, 4 + n_f);
  body.gcms.mass_matrix(0, 0) = 2.5;
  body.gcms.stiffness = Eigen::MatrixXd::Random(3 * n_f, 3 * n_f);
  body.gcms.mode_coefficients = Eigen::MatrixXd::Random(n_f, 9);
  ff::Interface face;
  face.name = "bore";
  face.y_row = Eigen::VectorXd::Random(4 + n_f);
  face.rotation = Eigen::MatrixXd::Random(3, 3 * n_f);
  body.interfaces.push_back(face);
  ff::RecoveryRegion region;
  region.name = "fillet";
  region.nodes.resize(2);
  region.nodes << 0, 3;
  region.stress_modes = Eigen::MatrixXd::Random(12, 3 * n_f);
  body.recovery.push_back(region);
  return body;
}

}  // namespace

TEST(BodyModel, FirstKModesAreTheLeadingBlocks) {
  const ff::BodyData body = synthetic_body();
  const Eigen::Index expected_fields[] = {0, 3, 5, 6};
  for (Eigen::Index k = 0; k <= 3; ++k) {
    SCOPED_TRACE(k);
    const fr::BodyModel model = fr::make_body_model(body, k, "synthetic.fbh5");
    const Eigen::Index n_f = expected_fields[k];
    ASSERT_EQ(model.field_count(), n_f);
    EXPECT_EQ(model.rigid(), k == 0);
    EXPECT_EQ(model.coordinate_count(), 12 + 3 * n_f);
    EXPECT_EQ(model.mass_matrix, body.gcms.mass_matrix.topLeftCorner(4 + n_f, 4 + n_f));
    EXPECT_EQ(model.stiffness, body.gcms.stiffness.topLeftCorner(3 * n_f, 3 * n_f));
    EXPECT_EQ(model.tisserand, body.gcms.mass_matrix.block(1, 4, 3, n_f));
    EXPECT_EQ(model.interfaces[0].y_row, body.interfaces[0].y_row.head(4 + n_f));
    EXPECT_EQ(model.interfaces[0].rotation, body.interfaces[0].rotation.leftCols(3 * n_f));
    EXPECT_EQ(model.recovery[0].stress_modes, body.recovery[0].stress_modes.leftCols(3 * n_f));
    EXPECT_EQ(model.recovery[0].name, body.recovery[0].name);
    EXPECT_EQ(model.recovery[0].nodes, body.recovery[0].nodes);
    EXPECT_TRUE(fr::make_body_model(body, k, "synthetic.fbh5", /*with_recovery=*/false).recovery.empty());
    EXPECT_EQ(model.fields, body.gcms.fields.leftCols(n_f));
    EXPECT_EQ(model.mode_coefficients, body.gcms.mode_coefficients.topLeftCorner(n_f, 3 * k));
    EXPECT_EQ(model.frequencies_hz, body.modes.frequencies_hz.head(k));
  }
  EXPECT_EQ(fr::make_body_model(body, std::nullopt).field_count(), 6);
}

TEST(BodyModel, RefusesMoreModesThanTheFileHolds) {
  const ff::BodyData body = synthetic_body();
  try {
    (void)fr::make_body_model(body, 4, "bar.fbh5");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "bar.fbh5: 4 modes asked for, the file holds 3");
  }
  EXPECT_THROW((void)fr::make_body_model(body, -1), std::invalid_argument);
}

namespace {

// (G ⊗ I3) x with G formed explicitly.
Eigen::VectorXd explicit_mass_times(const Eigen::MatrixXd& g, const Eigen::VectorXd& x) {
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(3 * g.rows(), 3 * g.cols());
  for (Eigen::Index r = 0; r < g.rows(); ++r)
    for (Eigen::Index c = 0; c < g.cols(); ++c) m.block<3, 3>(3 * r, 3 * c).diagonal().setConstant(g(r, c));
  return m * x;
}

}  // namespace

// A body file's fields are M_s-orthonormal, so G_ff is I to round-off: the model makes it exactly I and its mass
// products skip the n_f-square block. A G_ff that is not I keeps the general product.
TEST(BodyModel, OrthonormalFieldsGiveTheShortMassProduct) {
  ff::BodyData body = synthetic_body();
  const Eigen::Index n_f = 6;
  Eigen::MatrixXd g = Eigen::MatrixXd::Random(4 + n_f, 4 + n_f);
  g = (g + g.transpose()).eval();
  Eigen::MatrixXd noise = 1e-14 * Eigen::MatrixXd::Random(n_f, n_f);
  g.bottomRightCorner(n_f, n_f) = Eigen::MatrixXd::Identity(n_f, n_f) + noise + noise.transpose();
  body.gcms.mass_matrix = g;
  const Eigen::VectorXd x = Eigen::VectorXd::Random(3 * (4 + n_f));
  for (Eigen::Index k : {0, 2, 3}) {
    SCOPED_TRACE(k);
    const fr::BodyModel model = fr::make_body_model(body, k);
    const Eigen::Index f = model.field_count(), n = 3 * (4 + f);
    EXPECT_TRUE(model.unit_field_mass);
    EXPECT_EQ(model.mass_matrix.bottomRightCorner(f, f), Eigen::MatrixXd::Identity(f, f));
    EXPECT_EQ(model.mass_matrix.topRows(4), g.topLeftCorner(4, 4 + f));  // the rigid rows are untouched
    // Sums of at most 4 + n_f products of entries below 2 in size: 1e-14 is a few hundred ε.
    EXPECT_LE((fr::mass_times(model, x.head(n)) - explicit_mass_times(model.mass_matrix, x.head(n))).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_NEAR(fr::field_mass_norm_squared(model, x.head(3 * f)), x.head(3 * f).squaredNorm(), 1e-14);
  }
  g.bottomRightCorner(n_f, n_f).diagonal().array() += 1e-6;  // no longer I to round-off: G is kept as it is
  body.gcms.mass_matrix = g;
  const fr::BodyModel model = fr::make_body_model(body, 3);
  EXPECT_FALSE(model.unit_field_mass);
  EXPECT_EQ(model.mass_matrix, g);
  EXPECT_LE((fr::mass_times(model, x) - explicit_mass_times(g, x)).cwiseAbs().maxCoeff(), 1e-14);
  const Eigen::VectorXd xi = x.tail(3 * n_f);
  EXPECT_NEAR(fr::field_mass_norm_squared(model, xi), xi.dot(explicit_mass_times(g.bottomRightCorner(n_f, n_f), xi)), 1e-13);
  fr::BodyModel claimed = model;  // the flag set by hand on a G_ff that is not I: a system refuses the body
  claimed.unit_field_mass = true;
  fr::System system;
  try {
    system.add_body("bar", claimed, fr::BodyState{});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("body 'bar': unit_field_mass is set, but G_ff is not exactly I"), std::string::npos)
        << e.what();
  }
}

// A rigid body a simulator builds without a body file: G = diag(m, J), refused with its name for a mass that is not
// positive and a second moment that is not symmetric positive semidefinite.
TEST(RigidBodyModel, HoldsMassAndSecondMomentAndRefusesNonsense) {
  const Eigen::Matrix3d j = Eigen::Vector3d(0.5, 0.2, 0.1).asDiagonal();
  const fr::BodyModel model = fr::rigid_body_model(2.0, j, "wheel");
  EXPECT_TRUE(model.rigid());
  EXPECT_EQ(model.coordinate_count(), 12);
  EXPECT_EQ(model.mass_matrix(0, 0), 2.0);
  EXPECT_EQ((model.mass_matrix.block<3, 3>(1, 1) - j).norm(), 0.0);
  EXPECT_EQ(model.mass_matrix.row(0).tail<3>().norm(), 0.0);
  for (const double mass : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()})
    EXPECT_THROW((void)fr::rigid_body_model(mass, j, "wheel"), std::invalid_argument);
  Eigen::Matrix3d asymmetric = j;
  asymmetric(0, 1) = 0.1;
  EXPECT_THROW((void)fr::rigid_body_model(2.0, asymmetric, "wheel"), std::invalid_argument);
  try {
    (void)fr::rigid_body_model(2.0, Eigen::Vector3d(0.5, -0.2, 0.1).asDiagonal(), "wheel");
    FAIL() << "a negative second moment was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("wheel"), std::string::npos) << e.what();
  }
}
