#pragma once
// flexbody/format/body_data.hpp: the in-memory image of a flexible body file (*.fbh5).
//
// formats/SCHEMA.md is the normative description of the file; this struct mirrors it one to one.
// Everything is SI (metres, kilograms, seconds, pascals). Node-interleaved conventions follow the
// paper (Zwölfer & Gerstmayr 2023): a nodal vector field is stored node by node (x, y, z of node 0,
// then of node 1, ...), Eq. (3); the reduction modes are stored in list format, Eq. (49).

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace flexbody::format {

using RowMatrixX3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using RowMatrixX4i = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 4, Eigen::RowMajor>;
using RowMatrixX3i = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// Element connectivity with as many columns as the element has nodes (4 or 10).
using RowMatrixXi = Eigen::Matrix<std::int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// The schema version this library writes: sealed files without a global heap (SCHEMA.md, "Seal").
inline constexpr int kFormatVersion = 4;
/// The previous version, unsealed, which this library still reads (and `fbprep seal` converts).
inline constexpr int kUnsealedFormatVersion = 3;
/// Value of the root attribute `format`.
inline constexpr const char* kFormatName = "flexbody";

/// Where a body file came from: enough to reproduce it.
struct Provenance {
  std::string created_by;     ///< tool and version, e.g. "fbprep 0.1.0"
  std::string created_utc;    ///< ISO 8601 time of writing, e.g. "2026-11-21T14:38:08Z"
  std::string source_file;    ///< file name of the input (no directory)
  std::string source_sha256;  ///< SHA-256 of the input file, lowercase hex
  std::string input_unit;     ///< length unit the input was read in ("mm", "cm", "m", "in")
  std::string unit_reason;    ///< why that unit was used (declared by the file, --unit, ...)
  /// The unit the input file declares, when the tool read one ("mm", "cm", "m", "in"); "" otherwise.
  /// Differs from input_unit when the user's unit overrode the declaration. Optional in the file.
  std::string declared_unit;
  /// Every option the tool ran with, as (name, value) in the order given; values as text.
  std::vector<std::pair<std::string, std::string>> options;
};

/// Linear-elastic isotropic material.
struct Material {
  std::string name;               ///< "steel", "aluminium", "titanium" or "custom"
  double youngs_modulus = 0.0;    ///< E [Pa]
  double poisson_ratio = 0.0;     ///< nu [-]
  double density = 0.0;           ///< rho [kg/m^3]
};

/// Rigid-body mass properties from the consistent mass matrix (exact for the tetrahedral mesh).
struct MassProperties {
  double mass = 0.0;                                            ///< [kg]
  Eigen::Vector3d center_of_mass_input = Eigen::Vector3d::Zero(); ///< [m], in the input frame
  Eigen::Matrix3d inertia_about_com = Eigen::Matrix3d::Zero();    ///< [kg m^2], body axes
};

/// The finite-element mesh in the body frame: origin at the centre of mass, axes parallel to the
/// input's. Input-frame coordinates are nodes + center_of_mass_input.
struct BodyMesh {
  RowMatrixX3d nodes;  ///< n_n x 3 [m], body frame
  /// n_e x 4 (element_order 1) or n_e x 10 (element_order 2: the corners, then the middles of the edges (0,1), (1,2),
  /// (2,0), (0,3), (1,3), (2,3), format/tet10_element.hpp), 0-based node indices, positive orientation.
  RowMatrixXi tets;
  /// n_t x 3, 0-based, counter-clockwise seen from outside. For element_order 2 each 6-node boundary face is split
  /// into its 4 corner-and-middle triangles (SCHEMA.md).
  RowMatrixX3i surface_triangles;
  int element_order = 1;  ///< 1: linear tetrahedra (4 nodes), 2: quadratic (10 nodes)

  /// Nodes per element: 4 or 10.
  [[nodiscard]] static constexpr int nodes_per_element(int order) { return order == 2 ? 10 : 4; }
};

/// The reduction basis.
struct Modes {
  std::string kind = "free-free";  ///< how the modes were computed: "free-free" or "craig-bampton"
  /// Elastic frequencies [Hz], ascending; rigid-body modes never appear here.
  Eigen::VectorXd frequencies_hz;
  /// ||K phi - omega^2 M phi|| / ||K phi|| for each mode, as computed by fbprep.
  Eigen::VectorXd relative_residuals;
  /// Ῡ of Eq. (49): n_n x 3 n_m, row i = [psi_1^(i)T ... psi_nm^(i)T], M-orthonormal modes
  /// (Psiᵀ M̄ Psi = I, unit kg^-1/2).
  Eigen::MatrixXd upsilon;
  /// Craig-Bampton only (empty otherwise): the fixed-interface frequencies [Hz], every rbe2 interface
  /// clamped, ascending.
  Eigen::VectorXd fixed_interface_frequencies_hz;
  std::string eigensolver;  ///< the backend that ran: "arpack", "spectra", "block-lanczos" or "slepc"
  double shift = 0.0;       ///< sigma of the shift-invert solve [rad^2/s^2]
  /// The unit loads ("load point:fx", ...: forces fx, fy, fz, moments mx, my, mz) whose residual static
  /// responses (static correction modes) are in the basis; empty if none.
  std::vector<std::string> static_loads;
  /// Free-free only: the last this many modes are the static correction modes (Ritz vectors, not
  /// eigenmodes: their frequencies are Ritz values, their residuals large). Craig-Bampton folds the static
  /// responses into its basis before orthonormalising, so every mode is a Ritz vector and this is 0.
  Eigen::Index static_correction_modes = 0;

  [[nodiscard]] Eigen::Index count() const { return frequencies_hz.size(); }
};

/// The constant blocks of the improved GCMS equations of motion (Zwölfer & Gerstmayr 2023; formulations.md, "The
/// Method": nodal fields and dependent fields). The modes' 3 n_m scalar fields (the columns of Ῡ) are replaced by an
/// M_s-orthonormal basis of their span, built in mode order, without the fields that add nothing new (n_f <= 3 n_m).
/// With Y = [1, X̄, Ῡ'] the positions are r = (Y ⊗ I3) q, q = [τ; a; ξ], ξ of length 3 n_f.
struct Gcms {
  /// Ῡ' (n_n x n_f) [kg^-1/2]: Ῡ'ᵀ M_s Ῡ' = I.
  Eigen::MatrixXd fields;
  /// For each field the mode it came from, non-decreasing in [0, n_m), at most 3 per mode: the first k
  /// modes are spanned (up to the dropped remainders) by the fields with field_mode < k, a prefix.
  Eigen::VectorXi field_mode;
  /// C = Ῡ'ᵀ M_s Ῡ (n_f x 3 n_m) [1]: column 3m + k is field k of mode m in the new fields.
  Eigen::MatrixXd mode_coefficients;
  /// G = Yᵀ M_s Y ((4 + n_f) square, symmetric positive definite): the mass matrix is G ⊗ I3 (Eq. 66).
  Eigen::MatrixXd mass_matrix;
  /// K̂ = (Ῡ' ⊗ I3)ᵀ K̄ (Ῡ' ⊗ I3) (3 n_f square, symmetric) [N/m per kg], Eq. 96; index 3f + k.
  Eigen::MatrixXd stiffness;
  /// A field is dropped if its Gram-Schmidt remainder is below this fraction of its mode's M-norm.
  double drop_tolerance = 0.0;
  /// λmax / λmin of Ῡᵀ M_s Ῡ (+inf: singular). Its fields all carry kg^-1/2, so it does not depend on the
  /// part's size or units.
  double condition_mode_gram_before = 0.0;
  /// λmax / λmin of G in SI units, built with the original fields (+inf: singular) and the stored G. G's
  /// blocks carry kg, kg m^2 and 1, so for the same shape these change with its size L (towards L^-5 for
  /// small parts, L^5 for large ones): informative only, and +inf is accepted for both.
  double condition_mass_before = 0.0;
  double condition_mass_after = 0.0;
  /// The same of the Jacobi-scaled G, D^-1/2 G D^-1/2 with D = diag G: free of the units of G's blocks, so
  /// equal (to round-off) for the same shape at every size; what limits a Cholesky factorization of G.
  /// The one before is absent (nullopt) in files written before fbprep recorded it.
  std::optional<double> condition_mass_scaled_before;
  double condition_mass_scaled_after = 0.0;

  [[nodiscard]] Eigen::Index field_count() const { return fields.cols(); }
};

/// A named set of surface nodes where a joint or a force acts, as a marker of the GCMS body
/// (formulations.md, "The Method": constraints and markers): its position and its small rotation are linear in q.
struct Interface {
  std::string name;
  /// "rbe3": the marker follows the area-weighted average motion of the nodes; "rbe2": the nodes
  /// move rigidly with the marker (a constraint of the reduction, see SCHEMA.md).
  std::string coupling = "rbe3";
  Eigen::VectorXi nodes;     ///< k node indices, ascending, unique
  Eigen::VectorXd weights;   ///< k weights (the nodes' shares of the selected surface area), sum 1
  Eigen::Vector3d reference_point = Eigen::Vector3d::Zero();  ///< Σ w_i X̄_i [m], body frame
  /// wᵀ Y (4 + n_f): the marker position is (y_rowᵀ ⊗ I3) q = τ + A X̄_c + Σ_f y_row[4+f] ξ_f.
  Eigen::VectorXd y_row;
  /// R (3 x 3 n_f) [kg^-1/2 m^-1]: the node set's small rotation in the body frame,
  /// θ̄ = R ξ̄, the weighted least-squares rigid fit of the nodes' displacements (Σ_f υ'_f(i) ξ̄_f).
  Eigen::MatrixXd rotation;
};

/// Stress recovery for one output region: σ̄ = S ξ̄ at the region's nodes (body axes), linear in the
/// body-frame field coordinates ξ̄ (ξ̄_f = Aᵀ ξ_f for field f).
struct RecoveryRegion {
  std::string name;
  Eigen::VectorXi nodes;  ///< k node indices, ascending, unique
  /// S (6 k x 3 n_f) [Pa kg^-1/2 m^-1]: row 6 j + c is stress component c (xx, yy, zz, xy, xz, yz) at
  /// nodes(j); column 3 f + d is the stress of the displacement field υ'_f e_d (field f along axis d):
  /// element-constant stresses of the linear tetrahedra, averaged to the nodes by element volume.
  Eigen::MatrixXd stress_modes;
};

/// The geometric stiffness of unit prestress cases (SCHEMA.md "Geometric stiffness";
/// preprocess/geometric_stiffness.hpp): the prestress of case k, weighted by λ_k, adds λ_k Ĝ_k to the stiffness
/// projected on Y = [1, X̄, Ῡ'] (as G projects the mass); the GCMS's K̂ gains λ_k (Ĝ_k[4:, 4:] ⊗ I3).
/// The geometric stiffness's load cases are named "centrifugal:<c>" and "<interface>:<l>", with c and l from these
/// lists, in this order (the six products ω_i ω_j; a unit force and moment along the body axes).
inline constexpr std::array<const char*, 6> kCentrifugalCases = {"xx", "yy", "zz", "xy", "xz", "yz"};
inline constexpr std::array<const char*, 6> kInterfaceLoadCases = {"fx", "fy", "fz", "mx", "my", "mz"};

struct GeometricStiffness {
  /// "centrifugal:xx", ":yy", ":zz", ":xy", ":xz", ":yz" (λ = ω_x², ..., ω_y ω_z [rad²/s²], ω the body's angular
  /// velocity, body axes) and "<interface>:fx" ... ":mz" (λ = the force [N] or the moment [N m] about its reference
  /// point that the interface carries into the body, body axes). Each balanced by inertia relief.
  std::vector<std::string> cases;
  /// Ĝ_k ((4 + n_f) square, symmetric, one per case): ∫ ∇Y_aᵀ σ_k ∇Y_b dV per unit λ_k; like G's, its blocks carry
  /// mixed units (N m per unit λ for (X̄, X̄), s⁻² per unit λ for (Ῡ', Ῡ'), the unit of K̂). Row and column 0 (the
  /// constant field, which has no gradient) are zero.
  std::vector<Eigen::MatrixXd> matrices;

  [[nodiscard]] bool empty() const { return cases.empty(); }
};

/// Everything a flexible body file holds.
struct BodyData {
  /// The file's format version as read (kFormatVersion or kUnsealedFormatVersion); the writer ignores it and
  /// always writes kFormatVersion.
  int format_version = kFormatVersion;
  /// As read: whether the file carried a seal that matched its bytes (SCHEMA.md, "Seal"); the writer ignores
  /// it and always seals.
  bool sealed = false;
  Provenance provenance;
  Material material;
  MassProperties mass;
  BodyMesh mesh;
  Modes modes;
  Gcms gcms;
  std::vector<Interface> interfaces;  ///< in the order the body spec names them; names unique
  std::vector<RecoveryRegion> recovery;  ///< output regions, in the body spec's order; names unique
  GeometricStiffness geometric_stiffness;  ///< optional: empty when fbprep was not asked for it
};

}  // namespace flexbody::format
