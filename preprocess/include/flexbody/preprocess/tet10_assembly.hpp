#pragma once
// flexbody/preprocess/tet10_assembly.hpp: quadratic tetrahedral meshes and their K̄ and M_s.
//
// The assembly writes into the graph's upper-triangle patterns (assembly.hpp) element colour by element colour, the
// elements of a colour in parallel (OpenMP): no triplet lists (the node graph and the colour lists live while it
// runs), and the same bits for any thread count. fbprep's meshes come from gmsh (gmsh_import.hpp, order 2, curved on
// the CAD); quadratic_mesh makes straight-sided ones from linear meshes (tests, benchmarks).

#include "flexbody/format/tet10_element.hpp"
#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

namespace flexbody::preprocess {

/// The linear mesh with a node added at the middle of each edge (shared by the elements around the edge): the same
/// straight-sided elements, quadratic. The corner nodes keep their indices; edge nodes follow in order of first use.
[[nodiscard]] Tet10Mesh quadratic_mesh(const TetMesh& linear);

struct Tet10Matrices {
  SparseMatrix stiffness;    ///< K̄ (3 n_n square, node-interleaved, upper triangle) [N/m]
  SparseMatrix scalar_mass;  ///< M_s (n_n square, upper triangle; M̄ = M_s ⊗ I3), consistent [kg]
};

/// K̄ (4-point rule) and the consistent M_s of every element (format/tet10_element.hpp), integrated by `rule`.
/// Throws std::invalid_argument naming an element whose Jacobian determinant is not positive at a Gauss point or a
/// node (the first one in the first colour that has one), or a node index out of range, or a node of no element.
[[nodiscard]] Tet10Matrices assemble_tet10(const Tet10Mesh& mesh, const Material& material,
                                           format::Tet10MassRule rule = format::Tet10MassRule::exact);

}  // namespace flexbody::preprocess
