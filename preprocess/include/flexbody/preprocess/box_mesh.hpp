#pragma once
// flexbody/preprocess/box_mesh.hpp: a structured tetrahedral mesh of a box, for benchmarks and tests that need a
// mesh whose size they control exactly (no CAD, no gmsh).

#include "flexbody/preprocess/tet_mesh.hpp"

namespace flexbody::preprocess {

/// The box [0, lx] x [0, ly] x [0, lz] [m] cut into nx x ny x nz cells, each split into 6 positively oriented
/// tetrahedra along its main diagonal (Kuhn's split: conforming across cells). Node (i, j, k) has index
/// (k (ny + 1) + j) (nx + 1) + i. Throws std::invalid_argument for non-positive sizes or counts.
[[nodiscard]] TetMesh box_mesh(double lx, double ly, double lz, int nx, int ny, int nz);

}  // namespace flexbody::preprocess
