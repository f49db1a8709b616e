#pragma once
// Meshes and references the tests build themselves: structured boxes, the Abaqus block.

#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/material.hpp"
#include "flexbody/preprocess/tet4_element.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <filesystem>
#include <string>

namespace flexbody::test {

/// The tests' data directory (tests/data in the source tree).
[[nodiscard]] std::filesystem::path data_dir();
/// A fresh empty directory named after the running test, under the build tree (build/test-scratch/).
[[nodiscard]] std::filesystem::path scratch_dir();

/// A structured mesh of the box [0, lx] x [0, ly] x [0, lz] with nx x ny x nz cells, each split into
/// six positively oriented tetrahedra around its main diagonal (Kuhn split: conforming across cells).
[[nodiscard]] preprocess::TetMesh box_mesh(double lx, double ly, double lz, int nx, int ny, int nz);

/// Nodes and C3D4 elements of an Abaqus .inp file (first *Node and *Element, type=C3D4 blocks),
/// node order as in the file (node k of the file is row k-1).
[[nodiscard]] preprocess::TetMesh read_abaqus_c3d4(const std::filesystem::path& path);

/// Nodes and C3D10 elements of an Abaqus .inp file, node order as in the file and in tet10_element.hpp.
[[nodiscard]] preprocess::Tet10Mesh read_abaqus_c3d10(const std::filesystem::path& path);

/// A symmetric matrix exported by Abaqus (*_STIF1.mtx, *_MASS1.mtx: "row col value", 1-based), full.
[[nodiscard]] preprocess::SparseMatrix read_abaqus_matrix(const std::filesystem::path& path, Eigen::Index size);

/// A mesh with its assembled stiffness and scalar mass (upper triangles).
struct AssembledMesh {
  preprocess::TetMesh mesh;
  preprocess::SparseMatrix stiffness, scalar_mass;
};
[[nodiscard]] AssembledMesh assemble(preprocess::TetMesh mesh, const preprocess::Material& material,
                                     preprocess::MassScheme scheme = preprocess::MassScheme::consistent);

/// The steel beam 1 x 0.05 x 0.05 m of validation/README.md meshed by gmsh (unstructured, mesh size
/// 0.02 m, ~700 nodes), nodes shifted to the centre of mass. Its bending modes come in nearly
/// degenerate pairs: the hard case for shift-invert Lanczos (a member of a pair is easily missed) and
/// for the GCMS fields (the pairs' fields are nearly dependent). A structured Kuhn-split box is no
/// good here: its cells are anisotropic along the cube diagonal and split the pairs by 20 %.
[[nodiscard]] const AssembledMesh& square_beam();

/// A steel wire 1 x 0.0025 x 0.0025 m (slenderness 400) as a structured box of 100 x 1 x 1 Kuhn-split cells
/// (404 nodes, 1212 DOFs: dense references are affordable). The element forces of its low bending modes nearly
/// cancel, so their residuals have rounding floors above 1e-8 (eigen_residual.hpp): 6.8e-8 free-free, 2.7e-6
/// clamped at x = 0. Its cross-section is one cell, which locks in bending (the free-free first mode is
/// 60.7 Hz against Euler-Bernoulli's 13.3 Hz): a case for the numerics, not for frequencies.
[[nodiscard]] const AssembledMesh& steel_wire();
/// The wire's end face x = 0 as an rbe2 interface about the centre of that face (the wire clamped there).
[[nodiscard]] preprocess::RigidInterface steel_wire_root();

}  // namespace flexbody::test
