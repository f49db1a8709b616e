#pragma once
// flexbody/runtime/body_model.hpp: the constant data of one improved-GCMS body (Zwölfer & Gerstmayr 2023,
// Eqs. 85-89; formulations.md, "The Method": nodal fields to constraints and markers), loaded from a body file and
// truncated to what a scene needs.
//
// Coordinates q = [τ (3); a = vec(A) (9, column-major, Eq. 27); ξ (3 n_f)], positions r = (Y ⊗ I3) q with
// Y = [1, X̄, Ῡ'] (Eq. 61), mass matrix G ⊗ I3 (Eq. 66, constant), elastic energy ½ ξ̄ᵀ K̂ ξ̄ with ξ̄_f = Aᵀ ξ_f
// (Eqs. 87, 96). A rigid body is the same with n_f = 0: one code path.

#include "flexbody/format/body_data.hpp"
#include "flexbody/runtime/gcms_elastic.hpp"
#include "flexbody/runtime/prestress.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace flexbody::runtime {

struct FfrfModel;

/// The field blocks of the full-order reference body (full_order.hpp), kept sparse: G_ff = M_s and K̂ = K̄ have
/// the mesh's sparsity, while G's first four rows (the rigid rows and their coupling to the fields) are dense.
struct SparseFieldBlocks {
  Eigen::SparseMatrix<double> mass;             ///< G_ff = M_s (n_f square, symmetric)
  Eigen::SparseMatrix<double> stiffness;        ///< K̂ = K̄ (3 n_f square, symmetric, node-interleaved)
  Eigen::Matrix<double, 4, Eigen::Dynamic> border;  ///< G[0:4, :] (4 x (4 + n_f))
  /// Ῡ' = T (n_n x n_f) when nodes share fields (the rbe2 node sets of full_order_model(BodyData)); empty: Ῡ' = I,
  /// field i is node i.
  Eigen::SparseMatrix<double, Eigen::RowMajor> fields;
  /// β [s] of stiffness-proportional (Rayleigh) damping of the deformation, D̂ = β K̄ on the body-frame nodal
  /// velocities (damping.hpp); 0: undamped. Set by damp_full_order (full_order.hpp).
  double stiffness_damping = 0.0;
};

/// One body's constant blocks. The GCMS fields are an M_s-orthonormal basis of the modes' fields built in mode
/// order (SCHEMA.md), so the first k modes are exactly the fields with field_mode < k and the leading blocks
/// of G, K̂, the markers and the stress modes: truncation is slicing.
struct BodyModel {
  std::string source;               ///< the body file (for messages)
  Eigen::Index modes = 0;           ///< modes kept (0: rigid)
  double mass = 0.0;                ///< [kg]
  Eigen::MatrixXd mass_matrix;      ///< G ((4 + n_f) square)
  /// G_ff = I exactly, so that (G ⊗ I3) products skip the n_f-square block. make_body_model sets it for a body
  /// file's M_s-orthonormal fields (SCHEMA.md), snapping G_ff to I where it is I to round-off; a model built by
  /// hand leaves it false and takes the general product.
  bool unit_field_mass = false;
  Eigen::MatrixXd stiffness;        ///< K̂ (3 n_f square) [s^-2]
  /// g_f = G[1:4, 4 + f] (3 x n_f) [kg^1/2 m]: the rotational Tisserand constraint is Σ_f g_f × ξ̄_f = 0 (Eq. 78).
  Eigen::Matrix<double, 3, Eigen::Dynamic> tisserand;
  std::vector<format::Interface> interfaces;      ///< y_row and rotation truncated to n_f
  std::vector<format::RecoveryRegion> recovery;   ///< stress modes truncated to 3 n_f columns
  Eigen::MatrixXd fields;                         ///< Ῡ' (n_n x n_f), for nodal displacements
  /// C (n_f x 3 k): mode m's displacement is Σ_f,d C(f, 3m + d) Ῡ'_f e_d, so its modal coordinate in a state is
  /// η_m = Σ_f,d C(f, 3m + d) ξ̄_f[d] (the modes are M-orthonormal), and a pure mode m has ξ̄_f = η C(f, 3m..3m+2).
  Eigen::MatrixXd mode_coefficients;
  Eigen::VectorXd frequencies_hz;                 ///< of the k modes kept
  /// The lowest elastic frequency [Hz] the body shows: its first mode's, or for a Craig-Bampton basis its first
  /// clamped (fixed-interface) frequency if that is lower; 0 when unknown (rigid, full-order or built by hand). The
  /// integrator compares the body's spin with it (GeneralizedAlphaOptions::spin_limit).
  double lowest_frequency_hz = 0.0;
  /// D̂ (3 n_f square) [1/s] on the body-frame field velocities (damping.hpp); empty: undamped.
  Eigen::MatrixXd damping;
  format::RowMatrixX3d nodes;                     ///< X̄ (body frame) [m]
  format::RowMatrixX3i surface_triangles;         ///< the mesh's boundary, for pictures (paraview_series.hpp)
  /// Set for the full-order reference body only: its G and K̂ live here, sparse, and `mass_matrix`,
  /// `stiffness` and `fields` (Ῡ' = I or the sparse T) are empty. Use the accessors below rather than the dense members.
  std::shared_ptr<const SparseFieldBlocks> sparse;
  /// Set when the body moves in floating-frame coordinates [τ; p; η] (ffrf_model.hpp) instead of the improved
  /// GCMS's [τ; a; ξ]: the same modes, markers and outputs, another formulation. The GCMS members stay (markers,
  /// stresses and pictures are made from them).
  std::shared_ptr<const FfrfModel> floating_frame;
  /// The geometric stiffness of its prestress cases (prestress.hpp), when the body file holds them; null: the body
  /// has no geometric stiffening (a scene turns it off by resetting this).
  std::shared_ptr<const Prestress> prestress;

  /// G[0, 4:] (n_f): zero when every field is M-orthogonal to translations (every body file); otherwise (the
  /// full-order reference, full_order.hpp) the translational Tisserand rows Σ_f G[0, 4 + f] ξ_f = 0 (Eq. 77) are
  /// imposed too.
  [[nodiscard]] bool needs_translational_tisserand() const {
    // |G[0, 4 + f]| = |∫ φ_f dm| ≤ √(m G_ff(f, f)) (Cauchy-Schwarz): compared with that bound, so that the test reads
    // the same at any part size and for fields of any unit (round-off of 1e-15 √m at 1 mm must not add Eq. 77 rows).
    for (Eigen::Index f = 0; f < field_count(); ++f) {
      const double g_ff = sparse ? sparse->mass.coeff(f, f) : mass_matrix(4 + f, 4 + f);
      if (std::abs(g_border(0, 4 + f)) > 1e-8 * std::sqrt(mass * std::abs(g_ff))) return true;
    }
    return false;
  }
  [[nodiscard]] Eigen::Index field_count() const { return sparse ? sparse->mass.rows() : stiffness.rows() / 3; }
  /// G(r, c) for one of G's first four rows (r < 4), dense or sparse body alike.
  [[nodiscard]] double g_border(int r, Eigen::Index c) const { return sparse ? sparse->border(r, c) : mass_matrix(r, c); }
  /// 12 + 3 n_f ([τ; a; ξ]), or 7 + n_m for a floating-frame body ([τ; p; η]).
  [[nodiscard]] Eigen::Index coordinate_count() const { return floating_frame ? 7 + modes : 12 + 3 * field_count(); }
  [[nodiscard]] bool rigid() const { return field_count() == 0; }
  [[nodiscard]] bool floating() const { return floating_frame != nullptr; }
};

/// A rigid body of `mass` [kg] and second moment J = ∫ x xᵀ dm [kg m²] about its centre of mass in its frame
/// (J = m diag(a², b², c²)/12 for an a x b x c box), for parts a simulator has no body file for: G = diag(m, J).
/// Throws std::invalid_argument naming `source` unless m > 0 and J is finite, symmetric and positive semidefinite.
[[nodiscard]] BodyModel rigid_body_model(double mass, const Eigen::Matrix3d& second_moment,
                                         const std::string& source = "rigid body");

/// The body of `file` with its first `modes` modes (nullopt: all; 0: rigid, from the mass properties in G).
/// Without `with_recovery` the stress modes are left out (BodyModel::recovery empty): a body whose stresses nothing
/// shows need not copy them (6.8 of the sample bracket file's 7.9 MB). Throws std::invalid_argument naming the file if
/// `modes` is negative or exceeds the modes it holds.
[[nodiscard]] BodyModel make_body_model(const format::BodyData& body, std::optional<Eigen::Index> modes,
                                        const std::string& source = "body", bool with_recovery = true);

/// (G ⊗ I3) x_b for one body's coordinates x_b (12 + 3 n_f), as three products with G, one per direction.
[[nodiscard]] Eigen::VectorXd mass_times(const BodyModel& model, const Eigen::Ref<const Eigen::VectorXd>& x_b);
/// The same into y (the size of x_b); without allocating for a body of unit field mass (every body file's).
void mass_times(const BodyModel& model, const Eigen::Ref<const Eigen::VectorXd>& x_b, Eigen::Ref<Eigen::VectorXd> y);
/// ξᵀ (G_ff ⊗ I3) ξ = ∫|u|² dm of the fields' displacement ξ (3 n_f) [kg m²].
[[nodiscard]] double field_mass_norm_squared(const BodyModel& model, const Eigen::Ref<const Eigen::VectorXd>& xi);
/// Row `node` of Ῡ' (n_f): the node's weights of the fields.
[[nodiscard]] Eigen::RowVectorXd field_row(const BodyModel& model, Eigen::Index node);
/// The elastic energy and forces (gcms_elastic.hpp) of the body's K̂, dense or sparse.
[[nodiscard]] ElasticForces body_elastic_forces(const BodyModel& model, const Eigen::Matrix3d& a, const VectorRef& xi);
[[nodiscard]] ElasticTangent body_elastic_tangent(const BodyModel& model, const Eigen::Matrix3d& a, const VectorRef& xi,
                                                  bool with_xi_xi);

/// How many GCMS fields the first k modes have (the fields with field_mode < k).
[[nodiscard]] Eigen::Index fields_of_first_modes(const format::Gcms& gcms, Eigen::Index k);

}  // namespace flexbody::runtime
