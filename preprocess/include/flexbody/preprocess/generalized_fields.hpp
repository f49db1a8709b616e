#pragma once
// flexbody/preprocess/generalized_fields.hpp: the scalar fields of the improved GCMS and the removal
// of their linear dependency (formulations.md, "The Method": dependent fields; Zwölfer & Gerstmayr 2023, Eqs. 49 and
// 59).
//
// GCMS gives every scalar field of Ῡ (component k of mode m, column 3m + k) its own 3-vector of
// coordinates, so fields that are (nearly) linearly dependent make Ῡᵀ M_s Ῡ and G singular: the
// bending pairs of a square beam (u_y of one mode = u_z of the other) are the classic case, and the
// tiny cross-components of a mode (u_z of a y-bending mode) add a scale disparity of many decades.
// The fix lives at the scalar level: replace Ῡ by an M_s-orthonormal basis of its column span,
// built by Gram-Schmidt in mode order, dropping every field that adds nothing new. Because the
// fields are processed in order and each decision depends only on the fields before it, the first
// k modes always give the same fields, whatever comes after: a prefix of modes stays a valid basis.

#include "flexbody/preprocess/tet_mesh.hpp"

#include <Eigen/Core>

namespace flexbody::preprocess {

struct GeneralizedFieldOptions {
  /// A field is dropped when its M_s-norm after projection onto the fields kept before it is below
  /// this fraction of its mode's M_s-norm (1 for M-orthonormal modes). The fields of exactly
  /// dependent modes leave remainders at the modes' own error (1e-10 for residuals of 1e-10); a
  /// remainder of 1e-8 contributes a displacement 1e8 times smaller than the mode's and is noise.
  double drop_tolerance = 1e-8;
};

/// An M_s-orthonormal basis of the span of Ῡ's columns, in mode order.
struct GeneralizedFields {
  /// Ῡ' (n_n x n_f): the kept fields, Ῡ'ᵀ M_s Ῡ' = I (unit kg^-1/2, like the modes).
  Eigen::MatrixXd upsilon;
  /// M_s Ῡ' (n_n x n_f), freshly multiplied, for the products that follow (G).
  Eigen::MatrixXd mass_upsilon;
  /// For each kept field, the mode it came from (non-decreasing): the first k modes are spanned by
  /// the fields with source_mode < k, which are a prefix of the columns.
  Eigen::VectorXi source_mode;
  /// C = Ῡ'ᵀ M_s Ῡ (n_f x 3 n_m): column 3m + k expresses field k of mode m in the new fields
  /// (exactly, up to the dropped remainders).
  Eigen::MatrixXd mode_coefficients;
  /// Remainder norm / mode norm of every input field (3 n_m), kept or not: the evidence for the
  /// drop decisions.
  Eigen::VectorXd relative_remainders;
  int dropped = 0;  ///< fields dropped (3 n_m - n_f)
};

/// Classical Gram-Schmidt with reorthogonalization where needed, in the M_s inner product, of the
/// columns of `upsilon` (n_n x 3 n_m, Eq. 49 layout): each mode's 3 fields as a block against the
/// fields kept before, then one by one.
[[nodiscard]] GeneralizedFields orthonormal_fields(const SparseMatrix& scalar_mass_upper,
                                                   const Eigen::MatrixXd& upsilon,
                                                   const GeneralizedFieldOptions& options = {});

/// Spectral condition number λmax / λmin of a symmetric positive semi-definite matrix (+infinity if it is
/// singular to working precision: its Jacobi-scaled form has λmin <= 0). λmin is found through the Jacobi
/// scaling, so it keeps its relative accuracy (about eps scaled_condition) when the rows carry different units
/// and λmin/λmax is far below eps: G in SI units of a 1 mm part, whose direct eigen solve gives noise.
[[nodiscard]] double spectral_condition(const Eigen::MatrixXd& symmetric);

/// λmax / λmin of D^-1/2 A D^-1/2 with D = diag(A): free of the units of A's rows and columns (G mixes kg,
/// kg m, kg m^2 and 1), hence the same for the same shape at every size, and what limits a Cholesky
/// factorization of A. +infinity if λmin <= 0.
[[nodiscard]] double scaled_condition(const Eigen::MatrixXd& symmetric);

}  // namespace flexbody::preprocess
