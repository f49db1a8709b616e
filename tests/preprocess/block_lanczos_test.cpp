// The block-lanczos eigensolver backend against ARPACK: the same eigenvalues and eigenspaces, M̄-orthonormal
// vectors at the rounding floor, for several block sizes, free-free and Craig-Bampton; and its refusals.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"
#include "test_meshes.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <string>

namespace fp = flexbody::preprocess;

namespace {

const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};
// Both methods stop when the Ritz estimates pass tol = 1e-12 (block Lanczos at 1e-14) relative to the shift-inverted
// eigenvalue; measured differences are below 1e-13 in the frequencies and 1e-10 in the spaces, so 1e-9 is a wide
// margin that still catches a missed or wrong mode (the square beam's pairs differ by less than 1 %).
constexpr double kSame = 1e-9;

Eigen::MatrixXd mass_times(const fp::SparseMatrix& scalar_mass, const Eigen::MatrixXd& x) {
  Eigen::MatrixXd y(x.rows(), x.cols());
  for (Eigen::Index k = 0; k < x.cols(); ++k) fp::apply_vector_mass(scalar_mass, x.col(k), y.col(k));
  return y;
}

// Same values, and the same space: Φ_aᵀ M̄ Φ_b is orthogonal (all principal angles zero) whatever basis each
// method picked inside a nearly degenerate pair.
void expect_same_modes(const Eigen::VectorXd& f_a, const Eigen::MatrixXd& phi_a, const Eigen::VectorXd& f_b,
                       const Eigen::MatrixXd& phi_b, const fp::SparseMatrix& scalar_mass) {
  ASSERT_EQ(f_a.size(), f_b.size());
  for (Eigen::Index k = 0; k < f_a.size(); ++k) EXPECT_NEAR(f_b(k) / f_a(k), 1.0, kSame) << "mode " << k + 1;
  const Eigen::MatrixXd s = phi_a.transpose() * mass_times(scalar_mass, phi_b);
  const Eigen::VectorXd cosines = Eigen::JacobiSVD<Eigen::MatrixXd>(s).singularValues();
  EXPECT_LT((cosines - Eigen::VectorXd::Ones(f_a.size())).cwiseAbs().maxCoeff(), kSame);
}

double to_floor(const fp::FreeFreeModes& modes) {
  return (modes.relative_residuals.array() / modes.residual_floors.array()).maxCoeff();
}

fp::FreeFreeModes free_free(const flexbody::test::AssembledMesh& model, int modes, fp::EigensolverBackend backend,
                            Eigen::Index block_size = 16) {
  fp::FreeFreeOptions options;
  options.modes = modes;
  options.solver.backend = backend;
  options.solver.block_size = block_size;
  return fp::free_free_modes(model.mesh.nodes, model.stiffness, model.scalar_mass, kSteel, options);
}

}  // namespace

TEST(BlockLanczos, MatchesArpackForEveryBlockSize) {
  // 12 modes of the square beam: three nearly degenerate bending pairs, torsion and axial modes; the 12th ends
  // inside no pair. Block size 1 is plain Lanczos with full reorthogonalization.
  const auto& beam = flexbody::test::square_beam();
  const fp::FreeFreeModes arpack = free_free(beam, 12, fp::EigensolverBackend::arpack);
  for (Eigen::Index b : {1, 4, 16}) {
    SCOPED_TRACE("block size " + std::to_string(b));
    const fp::FreeFreeModes block = free_free(beam, 12, fp::EigensolverBackend::block_lanczos, b);
    expect_same_modes(arpack.frequencies_hz, arpack.vectors, block.frequencies_hz, block.vectors, beam.scalar_mass);
    const Eigen::MatrixXd gram = block.vectors.transpose() * mass_times(beam.scalar_mass, block.vectors);
    EXPECT_LT((gram - Eigen::MatrixXd::Identity(12, 12)).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT(block.rigid_body_coupling, 1e-12);  // the deflated operator keeps the basis off the rigid modes
    // The residuals come near their rounding floors (eigen_residual.hpp), as ARPACK's do: the worst measured 22x
    // (b = 1), 4.6x (b = 4), 15x (b = 16), ARPACK's 2.9x. fbprep accepts up to max(1e-8, 20x floor); 30x here
    // still fails a method stopped two orders early (tol 1e-12 gave hundreds of times the floor on the bracket).
    EXPECT_LT(to_floor(block), 30.0);
    EXPECT_EQ(block.operator_applies % b, 0);  // whole blocks
  }
}

TEST(BlockLanczos, SlenderWireReachesItsRoundingFloor) {
  // The wire's low bending modes have residual floors above 1e-8 (test_meshes.hpp): a test relative to the
  // shift-inverted eigenvalue, not an absolute one, is what lets them converge at all.
  const auto& wire = flexbody::test::steel_wire();
  const fp::FreeFreeModes arpack = free_free(wire, 8, fp::EigensolverBackend::arpack);
  const fp::FreeFreeModes block = free_free(wire, 8, fp::EigensolverBackend::block_lanczos, 8);
  expect_same_modes(arpack.frequencies_hz, arpack.vectors, block.frequencies_hz, block.vectors, wire.scalar_mass);
  EXPECT_LT(to_floor(block), 30.0);
}

TEST(BlockLanczos, CraigBamptonMatchesArpack) {
  // The fixed-interface problem has no rigid modes and no deflation: the clamped wire, 6 fixed-interface modes.
  const auto& wire = flexbody::test::steel_wire();
  auto reduce = [&](fp::EigensolverBackend backend) {
    fp::CraigBamptonOptions options;
    options.fixed_interface_modes = 6;
    options.solver.backend = backend;
    options.solver.block_size = 4;
    return fp::craig_bampton_modes(wire.mesh.nodes, wire.stiffness, wire.scalar_mass, kSteel,
                                   {flexbody::test::steel_wire_root()}, options);
  };
  const fp::CraigBamptonModes arpack = reduce(fp::EigensolverBackend::arpack);
  const fp::CraigBamptonModes block = reduce(fp::EigensolverBackend::block_lanczos);
  ASSERT_EQ(block.fixed_interface_frequencies_hz.size(), 6);
  for (Eigen::Index k = 0; k < 6; ++k)
    EXPECT_NEAR(block.fixed_interface_frequencies_hz(k) / arpack.fixed_interface_frequencies_hz(k), 1.0, kSame)
        << "fixed-interface mode " << k + 1;
  expect_same_modes(arpack.frequencies_hz, arpack.vectors, block.frequencies_hz, block.vectors, wire.scalar_mass);
}

TEST(BlockLanczos, RefusesABasisLargerThanTheMesh) {
  // 27 nodes, 81 DOFs, rank 75 after the rigid modes: 64 basis vectors in whole blocks, too few for 8 modes and a
  // block of 64 beyond them.
  const auto cube = flexbody::test::assemble(flexbody::test::box_mesh(1.0, 1.0, 1.0, 2, 2, 2), kSteel);
  try {
    (void)free_free(cube, 8, fp::EigensolverBackend::block_lanczos, 64);
    FAIL() << "a basis larger than the mesh was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("block Lanczos: 8 modes in blocks of 64 need more than the 64 basis vectors "
                                         "this mesh allows (use --eigensolver arpack)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(fp::block_lanczos_basis_limit(26, 16, 1'000'000), 528);  // 20 x 26 = 520, rounded up to whole blocks
  EXPECT_EQ(fp::block_lanczos_basis_limit(26, 16, 81), 64);           // the deflated rank 75, whole blocks
}

TEST(BlockLanczos, IsNamedBlockLanczos) {
  EXPECT_EQ(fp::eigensolver_backend_from_string("block-lanczos"), fp::EigensolverBackend::block_lanczos);
  EXPECT_EQ(fp::to_string(fp::EigensolverBackend::block_lanczos), "block-lanczos");
  EXPECT_EQ(fp::eigensolver_backend_from_string("auto"), fp::EigensolverBackend::automatic);
}

TEST(BlockLanczos, AutoPicksItForLargeMeshesWhoseBasisFits) {
  using B = fp::EigensolverBackend;
  EXPECT_EQ(fp::resolve_backend(B::automatic, 49'999, 26), B::arpack);
  EXPECT_EQ(fp::resolve_backend(B::automatic, 50'000, 26), B::block_lanczos);
  EXPECT_EQ(fp::resolve_backend(B::automatic, 1'053'090, 26), B::block_lanczos);
  // At 1.05M DOFs 4 GiB hold 504 basis vectors (whole blocks of 8): 10 per mode fit 50 modes.
  EXPECT_EQ(fp::block_lanczos_basis_limit(50, 8, 1'053'090), 504);
  EXPECT_EQ(fp::resolve_backend(B::automatic, 1'053'090, 50), B::block_lanczos);
  EXPECT_EQ(fp::resolve_backend(B::automatic, 1'053'090, 51), B::arpack);
  for (B named : {B::arpack, B::spectra, B::block_lanczos, B::slepc})
    EXPECT_EQ(fp::resolve_backend(named, 1'000, 500), named);  // a backend asked for by name is kept
}

TEST(BlockLanczos, ModesNameTheBackendThatRan) {
  // What the report and the body file's /reduction/eigensolver say: never "auto".
  const auto& beam = flexbody::test::square_beam();  // ~2k DOFs: auto is arpack
  EXPECT_EQ(free_free(beam, 6, fp::EigensolverBackend::automatic).eigensolver, fp::EigensolverBackend::arpack);
  EXPECT_EQ(free_free(beam, 6, fp::EigensolverBackend::block_lanczos).eigensolver,
            fp::EigensolverBackend::block_lanczos);
  EXPECT_EQ(free_free(beam, 6, fp::EigensolverBackend::spectra).eigensolver, fp::EigensolverBackend::spectra);
}
