#pragma once
// shell_sewing.hpp (internal): solids from a CAD model that has surfaces but no volume. Exporters
// often write a part as its faces only; OpenCASCADE can sew faces that meet along the same curves into a shell and
// make the closed shell a solid. Works on the current gmsh model (OpenCASCADE kernel), before meshing.

namespace flexbody::preprocess::detail {

struct SewingOutcome {
  int surfaces = 0;    ///< faces before sewing
  int solids = 0;      ///< volumes after it (0: none could be made)
  int free_edges = 0;  ///< curves that bound only one face after sewing: where the shell is open (0 when closed)
  int shells = 0;      ///< connected groups of faces after sewing
  bool by_healing = false;  ///< OpenCASCADE's healing made the solid(s), not the sewn surface loop
};

/// Sews the model's faces with `tolerance` (gmsh's coordinates) and makes solids of the closed shells: OpenCASCADE's
/// healing (gmsh::model::occ::healShapes), then, if that made none, one surface loop of every face with sewing and a
/// volume of it. The model keeps whatever was made; synchronized.
SewingOutcome sew_shells_into_solids(double tolerance);

}  // namespace flexbody::preprocess::detail
