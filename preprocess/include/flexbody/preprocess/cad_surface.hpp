#pragma once
// flexbody/preprocess/cad_surface.hpp: a CAD surface (gmsh entity of dimension 2) of the meshed part,
// for interfaces selected by surface tag or physical group, and for `fbprep list-surfaces`.

#include "flexbody/preprocess/tet_mesh.hpp"

#include <string>
#include <vector>

namespace flexbody::preprocess {

struct CadSurface {
  int tag = 0;                      ///< gmsh's surface tag (for STEP/BREP/IGES: OpenCASCADE's face order)
  std::vector<std::string> groups;  ///< names of the physical groups (dimension 2) that contain it
  /// Its mesh triangles, indices into the tetrahedral mesh's nodes (with element order 2: into ImportedMesh::quadratic's
  /// nodes, each 6-node triangle split into four as mesh_topology.hpp's boundary_triangles does).
  RowMatrixX3i triangles;
  double area_m2 = 0.0;             ///< of the triangles (the faceted surface)
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();  ///< area centroid, input frame
};

}  // namespace flexbody::preprocess
