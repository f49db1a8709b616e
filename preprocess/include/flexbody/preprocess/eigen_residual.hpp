#pragma once
// flexbody/preprocess/eigen_residual.hpp: the residual of an approximate eigenpair of K̄φ = λM̄φ, the rounding
// floor it is judged against, and the acceptance test of fbprep's modes.
//
// The relative residual ρ = ‖K̄φ − λM̄φ‖₂ / ‖K̄φ‖₂ cannot be computed smaller than the rounding errors of forming
// it: the exact eigenvector rounded to double already leaves K̄δφ with |δφ| <= ε|φ|, and each product adds
// errors bounded entrywise by a small multiple of ε |K̄||φ| (resp. ε |λ||M̄||φ|). Its floor is therefore
//
//   floor = ε (‖ |K̄| |φ| ‖₂ + |λ| ‖ |M̄| |φ| ‖₂) / ‖K̄φ‖₂,   ε = DBL_EPSILON = 2.2e-16,
//
// with |·| entrywise absolute values and ‖·‖₂ the Euclidean norm of the vector (no weighting). For compact parts
// it is 1e-14 to 1e-9 (the bracket: at most 1e-10); for the low bending modes of slender parts the
// element forces in K̄φ nearly cancel (K̄φ = λM̄φ is small where |K̄||φ| is not), and the floor grows with the
// slenderness and with mesh refinement (about 4 times per halved element size): 2.9e-8 for the first clamped
// mode of a 1 × 0.04 × 0.02 m beam at 1659 nodes, 2.7e-6 for a 1 × 0.0025 × 0.0025 m wire. A fixed bound of 1e-8
// then refuses modes that double precision cannot improve.
//
// fbprep accepts an eigenpair when ρ <= max(kMinResidualBound, kResidualFloorFactor · floor): the old bound
// wherever it is attainable, and a fixed multiple of the mode's own floor where it is not.

#include "flexbody/preprocess/tet_mesh.hpp"

#include <Eigen/Core>

#include <string>

namespace flexbody::preprocess {

/// Residuals below this are accepted whatever the floor (relative to ‖K̄φ‖₂; for static solves to ‖b‖₂).
inline constexpr double kMinResidualBound = 1e-8;
/// How far above its rounding floor a converged residual may lie. Measured ρ / floor over about 1400 modes
/// (ARPACK and Spectra, tol 1e-12 and 0; free-free and fixed-interface; the bracket and gmsh box beams of
/// slenderness 5 to 400 at 170 to 21k nodes): 0.4 to 0.75 for the low bending modes, whose floors are the large
/// ones (at most 3.8 wherever the floor exceeds 1e-9, so that this factor decides); up to 8.6 for the axial and
/// torsion modes of slender beams, which carry errors of their bending neighbours at machine precision too; 14 for
/// Spectra at tol 1e-12 on a floor of 4e-12 (its tolerance, not rounding: 1.4 at tol 0). Modes that are not
/// converged lie far above: ARPACK stopped early (tol 1e-3 or 1e-6 where Lanczos converges slowly), 1.7e3 to
/// 5e10; a mode mixed with 1e-6 of another, 97 (eigen_residual_test.cpp). 20 leaves a factor 2.3 above the
/// largest converged ratio; a shift 1500 times the first frequency (ratio 30 to 45) is refused, as 1e-8 did.
inline constexpr double kResidualFloorFactor = 20.0;

/// The accepted bound for a residual with this floor: max(kMinResidualBound, kResidualFloorFactor · floor).
[[nodiscard]] double accepted_residual(double floor);

struct EigenResidual {
  double relative = 0.0;  ///< ‖K̄φ − λM̄φ‖₂ / ‖K̄φ‖₂
  double floor = 0.0;     ///< ε (‖|K̄||φ|‖₂ + |λ| ‖|M̄||φ|‖₂) / ‖K̄φ‖₂ (see the top of this file)
  [[nodiscard]] double to_floor() const { return relative / floor; }
  [[nodiscard]] bool accepted() const { return relative <= accepted_residual(floor); }
};

/// The index of the mode furthest above its accepted bound (largest residual / bound; a residual that is not a
/// number counts as refused), or -1 when every residual is accepted. `residuals` and `floors` as EigenResidual's.
[[nodiscard]] Eigen::Index worst_refused(const Eigen::Ref<const Eigen::VectorXd>& residuals,
                                         const Eigen::Ref<const Eigen::VectorXd>& floors);

/// "relative residual 1.2e-05, 4.1e+02 times its rounding floor 2.9e-08; accepted up to max(1e-08, 8 x floor) =
/// 2.3e-07", for refusals.
[[nodiscard]] std::string describe_refusal(double relative, double floor);

/// The residual and floor of (λ, φ) for K̄ (upper triangle, 3 n_n square) and M̄ = M_s ⊗ I3 (M_s upper,
/// n_n square): one pass over each matrix, M̄ never formed.
[[nodiscard]] EigenResidual eigen_residual(const SparseMatrix& stiffness_upper, const SparseMatrix& scalar_mass_upper,
                                           double lambda, const Eigen::Ref<const Eigen::VectorXd>& phi);

/// y = A x and z = |A| |x| (entrywise absolute values) for a symmetric A stored as its upper triangle, in one
/// pass over it. x must not overlap y or z.
void apply_symmetric_with_magnitude(const SparseMatrix& upper, const Eigen::Ref<const Eigen::VectorXd>& x,
                                    Eigen::Ref<Eigen::VectorXd> y, Eigen::Ref<Eigen::VectorXd> z);

/// y = (M_s ⊗ I3) x and z = (|M_s| ⊗ I3) |x| (= |M̄| |x|) for node-interleaved x, in one pass over M_s's
/// upper triangle. x must not overlap y or z.
void apply_vector_mass_with_magnitude(const SparseMatrix& scalar_mass_upper, const Eigen::Ref<const Eigen::VectorXd>& x,
                                      Eigen::Ref<Eigen::VectorXd> y, Eigen::Ref<Eigen::VectorXd> z);

}  // namespace flexbody::preprocess
