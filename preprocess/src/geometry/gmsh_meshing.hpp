#pragma once
// Meshing a model gmsh holds, and reading its tetrahedra and surfaces (gmsh_import.cpp's inner steps: the mesh at a
// size, checked against the CAD volume; not installed).

#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/mesh_refinement.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace flexbody::preprocess::detail {

inline constexpr int kGmshTet4 = 4;    // gmsh element type of the 4-node tetrahedron
inline constexpr int kGmshTet10 = 11;  // and of the 10-node one

// Tetrahedra gmsh would make at element size h: its nearly regular tetrahedra of edge h have volume
// h^3 / kTetrahedraPerCubedSize (mesh_refinement.hpp).
inline double estimated_elements(double volume, double h) {
  return kTetrahedraPerCubedSize * volume / (h * h * h);
}

// Decides the unit of the geometry as gmsh delivers it, and the factor to metres.
struct UnitDecision {
  LengthUnit geometry_unit;   // unit of the numbers in the file, and of every length the user gives
  std::optional<LengthUnit> declared;  // what the file declares, if fbprep reads it
  bool overrides = false;     // the user's unit replaced a different declared one
  double gmsh_to_metres;      // factor from gmsh's coordinates to metres
  double size_unit_to_gmsh;   // factor from geometry_unit (mesh size) to gmsh's coordinates
  std::string reason;
};

// The tetrahedra, and for every node tag the node's index in them (absent: not used by a tetrahedron). For second-order
// meshes also the quadratic mesh, whose first nodes are the linear mesh's (the corners, same indices) and whose
// mid-edge nodes follow; gmsh's 10-node order lists the edges (2,3) and (1,3) the other way round from
// format/tet10_element.hpp's, so its last two nodes are swapped.
struct GmshTetrahedra {
  TetMesh mesh;
  std::unordered_map<std::size_t, std::int32_t> index_of_tag;
  std::optional<Tet10Mesh> quadratic;
};

[[nodiscard]] GmshTetrahedra tetrahedra_from_gmsh(const std::string& name, int order);

// Every surface entity's triangles in the tetrahedral mesh's numbering, with its physical groups. A second-order
// mesh's 6-node triangles are split into their four triangles, as the body file's surface is (mesh_topology.hpp).
[[nodiscard]] std::vector<CadSurface> cad_surfaces(const std::unordered_map<std::size_t, std::int32_t>& index_of_tag,
                                                   int order);

// Area and centroid of each surface's triangles (nodes in metres).
void measure(std::vector<CadSurface>& surfaces, const RowMatrixX3d& nodes);

// Meshes the model at `size` (gmsh's coordinates), checked against the CAD solids' volume `solid` (nullopt: no
// check); the default size is refined until the mesh holds it, a size the user gave is refused if it does not
// (gmsh_meshing.cpp). `estimated`: the tetrahedra expected at `size`. Fills result's mesh size, refinement and
// curved-element repair.
[[nodiscard]] GmshTetrahedra mesh_resolving_the_volume(const std::string& name, double size, std::optional<double> solid,
                                                       const UnitDecision& unit, const GmshImportOptions& options,
                                                       ImportedMesh& result, double estimated);

}  // namespace flexbody::preprocess::detail
