#pragma once
// flexbody/preprocess/gcms_matrices.hpp: the constant matrices of the improved GCMS equations of
// motion (Zwölfer & Gerstmayr 2023), computed once in preprocessing (formulations.md, "The Method": nodal fields).
//
// With Y = [1, X̄, Ῡ] (n_n x (4 + n_f), one column per scalar nodal field) the positions are
// r = (Y ⊗ I3) q, q = [τ; a; ξ] (Eqs. 60-61), so the generalized mass matrix of Eq. 66 is G ⊗ I3.

#include "flexbody/preprocess/tet_mesh.hpp"

#include <Eigen/Core>

namespace flexbody::preprocess {

/// Y = [1, X̄, Ῡ] for body-frame nodes X̄ (n_n x 3) and scalar fields Ῡ (n_n x n_f).
[[nodiscard]] Eigen::MatrixXd generalized_field_matrix(const RowMatrixX3d& nodes, const Eigen::MatrixXd& fields);

/// G = Yᵀ M_s Y ((4 + n_f) square, symmetric): the mass matrix of Eq. 66 is G ⊗ I3.
[[nodiscard]] Eigen::MatrixXd gcms_mass_matrix(const SparseMatrix& scalar_mass_upper, const RowMatrixX3d& nodes,
                                               const Eigen::MatrixXd& fields);
/// The same with M_s fields already at hand (`mass_fields` = M_s Ῡ).
[[nodiscard]] Eigen::MatrixXd gcms_mass_matrix(const SparseMatrix& scalar_mass_upper, const RowMatrixX3d& nodes,
                                               const Eigen::MatrixXd& fields, const Eigen::MatrixXd& mass_fields);

/// K̂ = (Ῡ ⊗ I3)ᵀ K̄ (Ῡ ⊗ I3), Eq. 96 (3 n_f square, symmetric; row and column 3f + k is component
/// k of field f, the order of ξ in Eq. 59). K̄ is applied to a few fields at a time through its
/// stored upper triangle: neither Ῡ ⊗ I3 nor K̄'s lower half is ever formed.
[[nodiscard]] Eigen::MatrixXd reduced_stiffness(const SparseMatrix& stiffness_upper, const Eigen::MatrixXd& fields);

}  // namespace flexbody::preprocess
