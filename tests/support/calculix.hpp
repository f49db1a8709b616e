#pragma once
// CalculiX (ccx), an independent finite-element code, from the tests: an Abaqus .inp of a tetrahedral mesh, a run,
// and its printed eigenvalues and displacements.

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace flexbody::test {

/// Whether `ccx` is on the PATH.
[[nodiscard]] bool have_ccx();
/// CI sets FLEXBODY_REQUIRE_CCX=1 (scripts/test.sh): there a missing ccx fails instead of skipping, so that the
/// comparisons with an independent code cannot silently stop running.
[[nodiscard]] bool ccx_required();

/// At the top of a test that needs ccx: skips it where ccx is missing, or fails it where CI requires ccx.
#define FLEXBODY_REQUIRE_CCX_OR_SKIP()                                              \
  do {                                                                              \
    if (!::flexbody::test::have_ccx()) {                                            \
      if (::flexbody::test::ccx_required())                                         \
        FAIL() << "ccx not installed but FLEXBODY_REQUIRE_CCX is set";              \
      GTEST_SKIP() << "ccx not installed (scripts/setup.sh installs calculix-ccx)"; \
    }                                                                               \
  } while (false)

/// The mesh (C3D4, or C3D10 for 10 nodes per element: ccx's node order is Abaqus', and the body file's) with node sets
/// NALL and element set EALL, one isotropic material STEEL on EALL, then `rest` verbatim (boundary conditions, steps).
void write_inp(const std::filesystem::path& path, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
               const Eigen::Ref<const Eigen::MatrixXi>& tets, double youngs_modulus, double poisson_ratio, double density,
               const std::string& rest);

/// Runs `ccx -i job` in `dir` with one solver thread; false (and ADD_FAILURE naming the log) if it fails.
bool run_ccx(const std::filesystem::path& dir, const std::string& job);

/// The first `count` frequencies [rad/s] of the mesh with the `clamped` nodes held, at rest (`spin` 0) or prestressed by a
/// spin [rad/s] about the axis through `point` along `axis`: a geometrically nonlinear static step with the centrifugal
/// load (*DLOAD CENTRIF, NLGEOM), then *FREQUENCY as its perturbation, which has the stress stiffening and the spin
/// softening and no Coriolis. Job `job` in `dir`; empty (and a failure added) if ccx fails.
[[nodiscard]] std::vector<double> ccx_frequencies(const std::filesystem::path& dir, const std::string& job,
                                                  const Eigen::Ref<const Eigen::MatrixXd>& nodes,
                                                  const Eigen::Ref<const Eigen::MatrixXi>& tets, double youngs_modulus,
                                                  double poisson_ratio, double density, const Eigen::VectorXi& clamped,
                                                  double spin, const Eigen::Vector3d& point, const Eigen::Vector3d& axis,
                                                  int count);

/// The EIGENVALUE column of the first eigenvalue table in a .dat [rad²/s²].
[[nodiscard]] std::vector<double> read_eigenvalues(const std::filesystem::path& dat);

/// Node displacements from *NODE PRINT U (node label order), node-interleaved; NaN where none was printed.
[[nodiscard]] Eigen::VectorXd read_displacements(const std::filesystem::path& dat, Eigen::Index nodes);

}  // namespace flexbody::test
