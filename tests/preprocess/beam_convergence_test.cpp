// The steel beam 1 x 0.05 x 0.05 m, free-free: the first bending frequency approaches Timoshenko beam
// theory (263.46 Hz, ../shared/validation/README.md) from above as the mesh is refined.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "test_meshes.hpp"

#include <gtest/gtest.h>

#include <cstdio>

namespace fp = flexbody::preprocess;

TEST(BeamConvergence, FreeFreeBendingApproachesTimoshenko) {
  const fp::Material steel{"steel", 210e9, 0.3, 7850.0};
  const double timoshenko = 263.46;  // first free-free bending pair, Cowper kappa = 0.8497
  std::vector<double> errors, frequencies;
  for (int refinement : {1, 2, 4}) {
    const auto beam = flexbody::test::assemble(
        flexbody::test::box_mesh(1.0, 0.05, 0.05, 40 * refinement, 2 * refinement, 2 * refinement), steel);
    const fp::TetMesh& mesh = beam.mesh;
    fp::FreeFreeOptions options;
    options.modes = 2;
    const auto modes = fp::free_free_modes(mesh.nodes, beam.stiffness, beam.scalar_mass, steel, options);
    const double f = 0.5 * (modes.frequencies_hz(0) + modes.frequencies_hz(1));
    frequencies.push_back(f);
    errors.push_back(f / timoshenko - 1.0);
    std::printf("  %3d x %2d x %2d cells, %6ld DOFs: f1 = %.3f Hz, error %+.4f %%\n", 40 * refinement,
                2 * refinement, 2 * refinement, static_cast<long>(mesh.dof_count()), f, 100 * errors.back());
  }
  // Linear tetrahedra are too stiff in bending: the frequencies lie above and come down as h^2.
  for (std::size_t level = 0; level < errors.size(); ++level) EXPECT_GT(errors[level], 0.0) << level;
  for (std::size_t level = 1; level < errors.size(); ++level) {
    // Halving h divides the error by about 4; 3 leaves room for the part of the error that is the
    // difference between 3D elasticity and Timoshenko theory (~0.1 %), which does not converge away.
    EXPECT_GT(errors[level - 1] / errors[level], 3.0) << level;
  }
  // The finest mesh (39k DOFs) is still 3.3 % stiff; h^2 extrapolation of the last two meshes must
  // land on Timoshenko theory within the 3D-versus-beam-theory difference (0.5 %).
  EXPECT_LT(errors.back(), 0.04);
  const double extrapolated = frequencies[2] + (frequencies[2] - frequencies[1]) / 3.0;
  std::printf("  h^2 extrapolation: %.3f Hz (Timoshenko %.2f Hz)\n", extrapolated, timoshenko);
  EXPECT_NEAR(extrapolated, timoshenko, 0.005 * timoshenko);
}
