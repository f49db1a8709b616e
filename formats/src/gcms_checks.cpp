// gcms_checks.cpp: the checks of /gcms (SCHEMA.md, "GCMS constants"), part of check_structure,
// check_finite and check_ranges.
#include "body_checks.hpp"
#include "check_helpers.hpp"

#include <Eigen/Cholesky>

#include <limits>
#include <numbers>

namespace flexbody::format::detail {
namespace {

std::string shape(Eigen::Index rows, Eigen::Index cols) { return std::to_string(rows) + " x " + std::to_string(cols); }

void expect_shape(const Eigen::MatrixXd& m, Eigen::Index rows, Eigen::Index cols, const std::string& path,
                  const std::string& meaning, const std::string& context) {
  if (m.rows() != rows || m.cols() != cols)
    fail(context, path + " has shape " + shape(m.rows(), m.cols()) + ", expected " + shape(rows, cols) + " (" +
                      meaning + ")");
}

void fail_symmetric(const Eigen::MatrixXd& m, Eigen::Index r, Eigen::Index c, const std::string& path,
                    const std::string& context) {
  fail(context, path + " is not symmetric: " + path + index(r) + index(c) + " = " + number(m(r, c)) + " but " + path +
                    index(c) + index(r) + " = " + number(m(c, r)));
}

// Written symmetric to the last bit (averaged with its transpose); 1e-12 leaves room for writers that are
// merely careful. K̂'s entries all carry s^-2, so its largest entry is their scale.
void check_symmetric(const Eigen::MatrixXd& m, const std::string& path, const std::string& context) {
  if (m.size() == 0) return;
  const double scale = m.cwiseAbs().maxCoeff();
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < c; ++r)
      if (std::abs(m(r, c) - m(c, r)) > 1e-12 * scale) fail_symmetric(m, r, c, path, context);
}

// G's rows carry different units (kg^1/2, kg^1/2 m and 1 for the rows of τ, a and ξ, in the sense that
// G_rc / sqrt(G_rr G_cc) is a pure number), and their sizes differ by many decades for a small or a large
// part: entry (r, c) is measured against sqrt(G_rr G_cc), its own scale (the entry of the Jacobi-scaled
// D^-1/2 G D^-1/2), never against the largest entry of G. Needs a positive diagonal.
void check_symmetric_scaled(const Eigen::MatrixXd& m, const std::string& path, const std::string& context) {
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < c; ++r)
      if (std::abs(m(r, c) - m(c, r)) > 1e-12 * std::sqrt(m(r, r) * m(c, c))) fail_symmetric(m, r, c, path, context);
}

// K̂ = (Ῡ ⊗ I3)ᵀ K̄ (Ῡ ⊗ I3) is positive semi-definite: a negative eigenvalue is an elastic shape that releases
// energy, and the runtime would find it only as a failing Newton core or a motion that grows. K̂ + σ I with σ =
// 8 ε n max|K̂_ii| (the rounding of a matrix of that size) must have a Cholesky factor. (A pivoted LDLᵀ missed
// indefinite blocks with zero diagonal, [[0, a], [a, 0]].) An eigenvalue below −σ is refused; one
// above it cannot be told from rounding in a matrix whose largest entry is max|K̂_ii|. Valid files have eigenvalues of
// 1.5e-9 to 2.4e-2 times the largest, far above σ.
void check_semidefinite(const Eigen::MatrixXd& m, const std::string& path, const std::string& context) {
  if (m.size() == 0) return;
  const double largest = m.diagonal().cwiseAbs().maxCoeff();
  const double sigma = 8.0 * std::numeric_limits<double>::epsilon() * static_cast<double>(m.rows()) * largest;
  Eigen::MatrixXd shifted = m;
  shifted.diagonal().array() += sigma;
  if (!(largest > 0.0) || Eigen::LLT<Eigen::MatrixXd>(shifted).info() != Eigen::Success)
    fail(context, path + " is not positive semi-definite (K_hat + " + number(sigma) + " I has no Cholesky factor): "
                      "a deformation would release elastic energy");
}

void check_condition(double value, const std::string& path, const std::string& context) {
  if (std::isnan(value) || !(value >= 1.0))
    fail(context, path + " is " + number(value) + ", expected a condition number >= 1 (or inf)");
}

}  // namespace

void check_gcms_structure(const BodyData& body, const std::string& context) {
  const Gcms& gcms = body.gcms;
  const Eigen::Index n_n = body.mesh.nodes.rows(), n_m = body.modes.count(), n_f = gcms.field_count();
  if (gcms.fields.rows() != n_n || n_f > 3 * n_m)
    fail(context, "/gcms/fields has shape " + shape(gcms.fields.rows(), n_f) + ", expected " + std::to_string(n_n) +
                      " x n_f with n_f <= 3 n_m = " + std::to_string(3 * n_m));
  if (gcms.field_mode.size() != n_f)
    fail(context, "/gcms/field_mode has " + std::to_string(gcms.field_mode.size()) + " entries, expected n_f = " +
                      std::to_string(n_f) + " (the columns of /gcms/fields)");
  expect_shape(gcms.mode_coefficients, n_f, 3 * n_m, "/gcms/mode_coefficients", "n_f x 3 n_m", context);
  expect_shape(gcms.mass_matrix, 4 + n_f, 4 + n_f, "/gcms/G", "(4 + n_f) square", context);
  expect_shape(gcms.stiffness, 3 * n_f, 3 * n_f, "/gcms/K_hat", "3 n_f square", context);
  for (Eigen::Index f = 0; f < n_f; ++f) {
    const int m = gcms.field_mode(f);
    if (m < 0 || m >= n_m || (f > 0 && m < gcms.field_mode(f - 1)))
      fail(context, "/gcms/field_mode" + index(f) + " is " + std::to_string(m) +
                        ", expected a mode index in [0, n_m) not below the previous entry");
    if (f >= 3 && gcms.field_mode(f - 3) == m)
      fail(context, "/gcms/field_mode" + index(f) + ": mode " + std::to_string(m) +
                        " has more than 3 fields (a mode has 3 scalar fields)");
  }
}

void check_gcms_finite(const BodyData& body, const std::string& context) {
  const Gcms& gcms = body.gcms;
  check_values(gcms.fields, "/gcms/fields", context);
  check_values(gcms.mode_coefficients, "/gcms/mode_coefficients", context);
  check_values(gcms.mass_matrix, "/gcms/G", context);
  check_values(gcms.stiffness, "/gcms/K_hat", context);
  check_value(gcms.drop_tolerance, "/gcms/drop_tolerance", context);
  // condition_G_before and condition_G_after (SI units) may be inf: they depend on the part's size, and
  // a writer that computes them without scaling finds G singular for a small part. The unit-free
  // condition_G_scaled_after certifies the stored G.
  check_value(gcms.condition_mass_scaled_after, "/gcms/condition_G_scaled_after", context);
}

void check_gcms_ranges(const BodyData& body, const std::string& context) {
  const Gcms& gcms = body.gcms;
  if (!(gcms.drop_tolerance >= 0.0 && gcms.drop_tolerance < 1.0))
    fail(context, "/gcms/drop_tolerance is " + number(gcms.drop_tolerance) + ", expected 0 <= tolerance < 1");
  check_condition(gcms.condition_mode_gram_before, "/gcms/condition_mode_gram_before", context);
  check_condition(gcms.condition_mass_before, "/gcms/condition_G_before", context);
  check_condition(gcms.condition_mass_after, "/gcms/condition_G_after", context);
  if (gcms.condition_mass_scaled_before)
    check_condition(*gcms.condition_mass_scaled_before, "/gcms/condition_G_scaled_before", context);
  check_condition(gcms.condition_mass_scaled_after, "/gcms/condition_G_scaled_after", context);
  const Eigen::MatrixXd& g = gcms.mass_matrix;
  const Eigen::VectorXd diagonal = g.diagonal();
  for (Eigen::Index i = 0; i < diagonal.size(); ++i)
    if (!(diagonal(i) > 0.0))
      fail(context, "/gcms/G" + index(i) + index(i) + " is " + number(diagonal(i)) +
                        ", expected > 0 (G is a mass matrix: positive definite)");
  check_symmetric_scaled(g, "/gcms/G", context);
  check_symmetric(gcms.stiffness, "/gcms/K_hat", context);
  check_semidefinite(gcms.stiffness, "/gcms/K_hat", context);
  // G must agree with /mass: G[0][0] is the mass and G[1:4, 1:4] = X̄ᵀ M_s X̄ the second moments J, with
  // inertia tr(J) I - J. Both come from the same M_s; 1e-9 allows for the summation order.
  const double mass = body.mass.mass;
  if (std::abs(g(0, 0) - mass) > 1e-9 * mass)
    fail(context, "/gcms/G[0][0] = " + number(g(0, 0)) + " kg differs from /mass/total = " + number(mass) + " kg");
  const Eigen::Matrix3d second_moments = g.block<3, 3>(1, 1);
  const Eigen::Matrix3d inertia = second_moments.trace() * Eigen::Matrix3d::Identity() - second_moments;
  const double inertia_scale = body.mass.inertia_about_com.cwiseAbs().maxCoeff();
  if ((inertia - body.mass.inertia_about_com).cwiseAbs().maxCoeff() > 1e-9 * inertia_scale)
    fail(context, "/gcms/G[1:4][1:4] (second moments J) gives the inertia tr(J) I - J, which differs from "
                  "/mass/inertia_about_com by more than 1e-9 relative");
  // What the runtime relies on without checking (SCHEMA.md, "What G holds"): the frame at the centre of
  // mass (G[0][1:4] = 0, 1e-9 of m times the part's size), the fields M-orthogonal to translations so that
  // Eq. 77 holds identically (G[0][4:] = 0, 1e-8 of sqrt(m): the unit field's M-norm is 1), and the fields
  // M_s-orthonormal (G[4:][4:] = I to 1e-10; these entries are pure numbers, relative to the fields' unit
  // M_s-norm). All three are relative to the size of the entry they bound, so they hold at any part size.
  const Eigen::Index n_f = gcms.field_count();
  const double size = std::max(body.mesh.nodes.cwiseAbs().maxCoeff(), 1e-300);
  for (int j = 1; j < 4; ++j)
    if (std::abs(g(0, j)) > 1e-9 * mass * size)
      fail(context, "/gcms/G[0]" + index(j) + " = " + number(g(0, j)) +
                        " kg m: the first moment about the origin must vanish (body frame at the centre of mass)");
  for (Eigen::Index f = 0; f < n_f; ++f)
    if (std::abs(g(0, 4 + f)) > 1e-8 * std::sqrt(mass))
      fail(context, "/gcms/G[0]" + index(4 + f) + " = " + number(g(0, 4 + f)) +
                        ": field " + std::to_string(f) + " is not M-orthogonal to the translations (Eq. 77)");
  for (Eigen::Index r = 0; r < n_f; ++r)
    for (Eigen::Index c = 0; c < n_f; ++c)
      if (std::abs(g(4 + r, 4 + c) - (r == c ? 1.0 : 0.0)) > 1e-10)
        fail(context, "/gcms/G" + index(4 + r) + index(4 + c) + " = " + number(g(4 + r, 4 + c)) +
                          ": the fields are not M_s-orthonormal (G[4:][4:] must be I)");
  // C = Ῡ'ᵀ M_s Ῡ holds each mode's fields in the M_s-orthonormal new fields, so by Bessel's inequality the squares
  // of the 3 columns of mode m sum to ψ_mᵀ M̄ ψ_m = 1 (the modes are M-orthonormal, M̄ = M_s ⊗ I3) less the dropped
  // remainders: at most 3 of norm below drop_tolerance. Valid files give 1 to 1e-14 (free-free and Craig-Bampton,
  // 3 to 48 fields); 1e-9 leaves five decades for round-off in larger bases and still refuses any change to C
  // above its 30th bit, or a C scaled by a mistaken unit.
  const Eigen::MatrixXd& c = gcms.mode_coefficients;
  const double dropped = 3.0 * gcms.drop_tolerance * gcms.drop_tolerance;
  for (Eigen::Index m = 0; m < c.cols() / 3; ++m) {
    const double sum = c.middleCols(3 * m, 3).squaredNorm();
    if (!(sum <= 1.0 + 1e-9 && sum >= 1.0 - dropped - 1e-9))
      fail(context, "/gcms/mode_coefficients: the squares of columns " + std::to_string(3 * m) + " to " +
                        std::to_string(3 * m + 2) + " (mode " + std::to_string(m) + ") sum to " + number(sum) +
                        ", expected 1 (M-orthonormal modes in M_s-orthonormal fields; 1e-9 and the dropped "
                        "remainders allowed)");
  }
  // The stored frequencies are the modes' Rayleigh quotients: ψ_mᵀ K̄ ψ_m = ω_m² with ψ_m M-normal, and ψ_m in the
  // fields is ξ̄_f = C(f, 3m..3m+2), so c_mᵀ K̂ c_m = ω_m² (normal modes, Craig-Bampton and static corrections alike,
  // all K̄-orthogonal Ritz vectors). It ties /reduction/frequencies_hz, K̂ and C together: a K̂ or a frequency scaled
  // by a mistaken unit is refused. Valid files agree to 2e-9 (195 files: free-free, Craig-Bampton, static
  // corrections, 2 to 80 modes); 1e-6 allows for round-off in larger bases and for dropped fields' remainders.
  const Eigen::Index modes = c.cols() / 3;
  if (gcms.stiffness.rows() == 3 * c.rows() && body.modes.frequencies_hz.size() == modes) {
    Eigen::VectorXd shape(3 * c.rows());
    for (Eigen::Index m = 0; m < modes; ++m) {
      for (Eigen::Index f = 0; f < c.rows(); ++f) shape.segment<3>(3 * f) = c.row(f).segment<3>(3 * m).transpose();
      const double quotient = shape.dot(gcms.stiffness * shape);
      const double omega = 2.0 * std::numbers::pi * body.modes.frequencies_hz(m);
      if (!(std::abs(quotient - omega * omega) <= 1e-6 * omega * omega))
        fail(context, "/reduction/frequencies_hz" + index(m) + " = " + number(body.modes.frequencies_hz(m)) +
                          " Hz, but /gcms/K_hat and /gcms/mode_coefficients give mode " + std::to_string(m) + " " +
                          number(std::sqrt(std::max(quotient, 0.0)) / (2.0 * std::numbers::pi)) +
                          " Hz (c_mᵀ K̂ c_m = ω²; 1e-6 allowed)");
    }
  }
  // Positive definite, tested on the Jacobi-scaled matrix: the blocks of G carry different units
  // (kg, kg m, kg m^2, 1), and scaling makes the test independent of them (and of the part's size).
  const Eigen::VectorXd scale = diagonal.cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * g * scale.asDiagonal();
  if (Eigen::LLT<Eigen::MatrixXd>(scaled).info() != Eigen::Success)
    fail(context, "/gcms/G is not positive definite (its Cholesky factorization fails)");
}

}  // namespace flexbody::format::detail
