#pragma once
// flexbody/preprocess/rigid_body_modes.hpp: the six rigid-body fields of a free body, in closed form.

#include "flexbody/preprocess/tet_mesh.hpp"

#include <Eigen/Core>

namespace flexbody::preprocess {

/// The 3 translations and 3 small rotations (about the centre of mass) of the nodes, as a
/// 3 n_n x 6 node-interleaved matrix R, made M̄-orthonormal (Rᵀ M̄ R = I) with M̄ = M_s ⊗ I3.
[[nodiscard]] Eigen::MatrixXd rigid_body_modes(const RowMatrixX3d& nodes, const SparseMatrix& scalar_mass_upper);

}  // namespace flexbody::preprocess
