#pragma once
// flexbody/preprocess/gcms_constants.hpp: everything the body file's /gcms group holds, from the
// mesh, M_s, K̄ and the M-orthonormal modes (formulations.md, "The Method": nodal fields and dependent fields).

#include "flexbody/format/body_data.hpp"
#include "flexbody/preprocess/generalized_fields.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

namespace flexbody::preprocess {

/// Orthonormalises the modes' scalar fields (dropping dependent ones), then G = Yᵀ M_s Y and
/// K̂ = (Ῡ' ⊗ I3)ᵀ K̄ (Ῡ' ⊗ I3) with Y = [1, X̄, Ῡ'], and the condition numbers before and after:
/// spectral for Ῡᵀ M_s Ῡ, Jacobi-scaled (unit-free) for G.
/// `nodes` must be in the body frame (origin at the centre of mass); `upsilon` is n_n x 3 n_m (Eq. 49).
[[nodiscard]] format::Gcms gcms_constants(const SparseMatrix& stiffness_upper, const SparseMatrix& scalar_mass_upper,
                                          const RowMatrixX3d& nodes, const Eigen::MatrixXd& upsilon,
                                          const GeneralizedFieldOptions& options = {});

}  // namespace flexbody::preprocess
