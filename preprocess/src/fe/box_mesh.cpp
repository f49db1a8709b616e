#include "flexbody/preprocess/box_mesh.hpp"

#include <array>
#include <cstdint>
#include <stdexcept>
#include <utility>

namespace flexbody::preprocess {

TetMesh box_mesh(double lx, double ly, double lz, int nx, int ny, int nz) {
  if (!(lx > 0.0 && ly > 0.0 && lz > 0.0) || nx < 1 || ny < 1 || nz < 1)
    throw std::invalid_argument("box mesh: the sizes must be positive and the cell counts at least 1");
  TetMesh mesh;
  auto id = [&](int i, int j, int k) { return static_cast<std::int32_t>((k * (ny + 1) + j) * (nx + 1) + i); };
  mesh.nodes.resize(static_cast<Eigen::Index>(nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) mesh.nodes.row(id(i, j, k)) << lx * i / nx, ly * j / ny, lz * k / nz;
  // Kuhn split of the unit cube: the 6 paths from corner 0 to corner 7 that add one axis at a time.
  static constexpr std::array<std::array<int, 3>, 6> kPaths = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  mesh.tets.resize(6 * static_cast<Eigen::Index>(nx) * ny * nz, 4);
  Eigen::Index e = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& path : kPaths) {
          std::array<int, 3> offset = {0, 0, 0};
          std::array<std::int32_t, 4> corners{};
          corners[0] = id(i, j, k);
          for (int step = 0; step < 3; ++step) {
            offset[path[step]] = 1;
            corners[step + 1] = id(i + offset[0], j + offset[1], k + offset[2]);
          }
          // Orientation: an odd permutation of the axes gives a negative volume; swap to fix it.
          const bool odd = (path[0] == 0 && path[1] == 2) || (path[0] == 1 && path[1] == 0) ||
                           (path[0] == 2 && path[1] == 1);
          if (odd) std::swap(corners[2], corners[3]);
          for (int a = 0; a < 4; ++a) mesh.tets(e, a) = corners[a];
          ++e;
        }
  return mesh;
}

}  // namespace flexbody::preprocess
