// Geometric stiffening of a disk on a rigid hub against CalculiX (issue 29): a steel annulus held at its bore (an rbe2
// interface, Craig-Bampton) and spun about its axis. Its prestress is the hoop and radial stress of a disk whose bore
// the hub keeps from expanding: the prestress cases must hold the rbe2 patch rigid as the modes do (solved on the free
// part, the bore expanded, and the stiffening of its first eight modes was 25-33 % off CalculiX's).
//
// The runtime's linearisation about the steady spin in the bore's frame (the FFRF with frame: {interface: bore}),
// without Coriolis as ccx's *FREQUENCY has it: (K_ff + Σ λ_k K_g,k − Ω² S) η = ω² M_ff η, where S_mn = ∫ρ (e × ψ_m)·
// (e × ψ_n) = tr J2_mn − eᵀ J2_mn e is the spin softening and λ the steady spin's weights: ω̄_i ω̄_j, and at the bore
// the force m a_cm = −m Ω² (I − e eᵀ)(c − p) and the moment ω × (I_p ω) about its reference point p, into the body
// (both zero for this disk; the same code on the cantilever of stiffening_test.cpp meets ccx within 0.1 %).
#include "calculix.hpp"
#include "cli_run.hpp"
#include "flexbody/format/body_file.hpp"
#include "flexbody/runtime/body_model.hpp"
#include "flexbody/runtime/ffrf_model.hpp"
#include "flexbody/runtime/prestress.hpp"
#include "test_meshes.hpp"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <vector>

namespace fr = flexbody::runtime;

namespace {

struct Disk {
  std::filesystem::path dir;
  flexbody::format::BodyData data;
};

// A steel annulus, outer radius 60 mm, bore 15 mm, 3 mm thick, in the x-y plane: the bore is an rbe2 interface
// (Craig-Bampton, 12 fixed-interface modes), quadratic tetrahedra of 4 mm, with the geometric stiffness.
const Disk& disk() {
  static const Disk d = [] {
    Disk out;
    out.dir = flexbody::test::scratch_dir();
    flexbody::test::write_text(out.dir / "disk.geo", "SetFactory(\"OpenCASCADE\");\n"
                                                     "Cylinder(1) = {0, 0, 0, 0, 0, 0.003, 0.06};\n"
                                                     "Cylinder(2) = {0, 0, 0, 0, 0, 0.003, 0.015};\n"
                                                     "BooleanDifference(3) = {Volume{1}; Delete;}{Volume{2}; Delete;};\n");
    flexbody::test::write_text(out.dir / "disk.yaml", R"(input: disk.geo
unit: m
material: steel
mesh: {size: 0.004}
reduction: {kind: craig-bampton, modes: 12}
interfaces:
  bore: {select: {cylinder: {point: [0, 0, 0], direction: [0, 0, 1], radius: 0.015}}, coupling: rbe2}
geometric_stiffness: true
)");
    const flexbody::test::CliRun prep = flexbody::test::run_fbprep(out.dir, "disk.yaml -o disk.fbh5 -q");
    EXPECT_EQ(prep.exit_code, 0) << prep.err;
    out.data = flexbody::format::read_body_file(out.dir / "disk.fbh5");
    return out;
  }();
  return d;
}

// The runtime's stiffened frequencies [rad/s] of the disk held at its bore spinning at `spin` about z, lowest first.
std::vector<double> runtime_frequencies(double spin) {
  fr::BodyModel model = fr::make_body_model(disk().data, std::nullopt, "disk");
  const fr::FfrfModel f = fr::make_ffrf_model(model, fr::FloatingFrame::interface, model.interfaces[0].name);
  const fr::Prestress& prestress = *model.prestress;
  const Eigen::Vector3d e = Eigen::Vector3d::UnitZ(), omega = spin * e;
  const Eigen::Vector3d p = model.interfaces[0].reference_point;  // body frame: the centre of mass is the origin
  const Eigen::Vector3d c = -p;                                   // the centre of mass from p
  const Eigen::Matrix3d j = f.second_moment;                      // ∫ρ x̄ x̄ᵀ about the centre of mass
  const Eigen::Matrix3d inertia_cm = j.trace() * Eigen::Matrix3d::Identity() - j;
  const Eigen::Matrix3d inertia_p = inertia_cm + f.mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  std::vector<fr::InterfaceLoad> loads(model.interfaces.size());
  loads[0].force = -f.mass * spin * spin * (c - e * e.dot(c));
  loads[0].moment = omega.cross(inertia_p * omega);
  Eigen::VectorXd weights;
  fr::prestress_weights(prestress, omega, loads, weights);
  Eigen::MatrixXd k_g;
  fr::weighted_sum(f.prestress, weights, k_g);
  const Eigen::Index n = f.modes;
  Eigen::MatrixXd softening(n, n);
  for (Eigen::Index m = 0; m < n; ++m)
    for (Eigen::Index k = 0; k < n; ++k) {
      const Eigen::Matrix3d j2 = f.mode_products.block<3, 3>(3 * m, 3 * k);
      softening(m, k) = j2.trace() - e.dot(j2 * e);
    }
  const Eigen::MatrixXd stiffness = f.modal_stiffness + k_g - spin * spin * softening;
  const Eigen::VectorXd values =
      Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (stiffness + stiffness.transpose()), f.modal_mass,
                                                                Eigen::EigenvaluesOnly)
          .eigenvalues();
  std::vector<double> frequencies;
  for (Eigen::Index k = 0; k < values.size(); ++k) frequencies.push_back(std::sqrt(std::max(values(k), 0.0)));
  return frequencies;
}

}  // namespace

// Measured: at rest the two agree to 2e-6 (ccx's 4-point C3D10 mass); at 0.5 ω₁ (3661 rad/s) within 5e-4 and at ω₁
// within 0.41 % in the first eight modes (the pairs of one and two nodal diameters and the umbrella mode), where the
// spin softening, the stiffening of the clamped bore and ccx's nonlinear geometry (the rim expands by 0.7 % of the
// radius there) all show. Asserted: 1e-5, 1e-3 and issue 29's 1 %.
TEST(GeometricStiffening, TheSpinningDiskAgreesWithCalculiX) {
  FLEXBODY_REQUIRE_CCX_OR_SKIP();
  const flexbody::format::BodyData& body = disk().data;
  const flexbody::format::Interface& bore = body.interfaces[0];
  const double omega_1 = 2 * std::numbers::pi * body.modes.fixed_interface_frequencies_hz(0);
  std::vector<double> ccx_rest, ours_rest;
  for (const auto& [ratio, tolerance] : std::vector<std::pair<double, double>>{{0.0, 1e-5}, {0.5, 1e-3}, {1.0, 1e-2}}) {
    const double spin = ratio * omega_1;
    const std::vector<double> ccx = flexbody::test::ccx_frequencies(
        disk().dir, fmt::format("spin{}", static_cast<int>(100 * ratio)), body.mesh.nodes, body.mesh.tets,
        body.material.youngs_modulus, body.material.poisson_ratio, body.material.density, bore.nodes, spin,
        bore.reference_point, Eigen::Vector3d::UnitZ(), 8);
    ASSERT_EQ(ccx.size(), 8u);
    const std::vector<double> ours = runtime_frequencies(spin);
    for (std::size_t k = 0; k < 8; ++k)
      EXPECT_NEAR(ours[k] / ccx[k], 1.0, tolerance) << "mode " << k + 1 << " at " << ratio << " omega_1";
    if (ratio == 0.0) {
      ccx_rest = ccx;
      ours_rest = ours;
    }
    // The stiffening itself, (ω² − ω₀²)/Ω² per mode (1.38 for the first): the frequencies' ratios dilute its error
    // where it is small beside ω₀² (the higher modes). Measured within 0.3 % at 0.5 ω₁; before the fix, 25-33 % off.
    if (ratio == 0.5)
      for (std::size_t k = 0; k < 8; ++k) {
        const double theirs = (ccx[k] * ccx[k] - ccx_rest[k] * ccx_rest[k]) / (spin * spin);
        EXPECT_NEAR((ours[k] * ours[k] - ours_rest[k] * ours_rest[k]) / (spin * spin) / theirs, 1.0, 0.02)
            << "mode " << k + 1;
      }
  }
}
