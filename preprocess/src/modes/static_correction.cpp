#include "flexbody/preprocess/static_correction.hpp"

#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/eigen_residual.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <cfloat>
#include <cmath>
#include <functional>
#include <stdexcept>

namespace flexbody::preprocess {
namespace {

// The conjugate-gradient iteration stops when its residual is below this fraction of the projected load.
// The preconditioned spectrum lies in [λ_next / (λ_next − σ), 1), so this takes a few solves when |σ| is
// below the first eigenvalue not in the basis (about 3 per load on the bracket); kMaxIterations leaves room
// for very slender parts. The true residual b − PᵀK̄u is checked afterwards (the recursive one can drift from
// it, and keeps falling where the true one stops at its rounding floor); one restart from u is allowed before
// the load is refused. The check is that of the eigenmodes (eigen_residual.hpp): ‖b − PᵀK̄u‖₂ / ‖b‖₂ <=
// max(1e-8, kResidualFloorFactor · floor), floor = ε ‖|K̄||u|‖₂ / ‖b‖₂, the rounding error of forming K̄u. The
// projection adds no cancellation (K̄u is M̄W-free at the solution), so its own rounding, ε‖b‖-sized, is left out.
// With rigid patches (relieved_static_responses) Q removes the patches' constraint forces from K̄u too, which can be
// much larger than ‖Qf‖; the floor, from ‖|K̄||u|‖ >= ‖K̄u‖, covers their rounding. There the preconditioned spectrum
// is no longer bounded by 1 and the iterations grow with the patches' size (66 per load on a disk's bore).
constexpr double kSolveTolerance = 1e-10;
constexpr int kMaxIterations = 500;
// A combination of M̄-normalised responses whose M̄-norm is below 1e-6 adds nothing the others and the known
// fields do not already hold (the responses themselves are accurate to ~1e-10): Gram eigenvalue 1e-12.
constexpr double kDependentGram = 1e-12;
// Loads solved together (one block solve per CG iteration): a pass over the factor costs little more for 16
// right-hand sides than for 8 (bench/block_solve_bench), and the work matrices stay six n x 16.
constexpr Eigen::Index kStaticBatch = 16;

// P x = x − W (Wᵀ M̄ x): the M̄-orthogonal projection onto the complement of the known fields. M̄ is applied on
// the fly (one sparse product) rather than storing M̄W, which would double the memory of W at 1M DOFs.
void project(const Eigen::MatrixXd& known, const SparseMatrix& mass, Eigen::Ref<Eigen::VectorXd> x) {
  if (known.cols() == 0) return;
  Eigen::VectorXd mx(x.size());
  apply_vector_mass(mass, x, mx);
  x -= known * (known.transpose() * mx);
}

// Pᵀ x = x − M̄ W (Wᵀ x): the transposed projection, for forces.
void project_force(const Eigen::MatrixXd& known, const SparseMatrix& mass, Eigen::Ref<Eigen::VectorXd> x) {
  if (known.cols() == 0) return;
  const Eigen::VectorXd w = known * (known.transpose() * x);
  Eigen::VectorXd mw(x.size());
  apply_vector_mass(mass, w, mw);
  x -= mw;
}

// Π: each rigid patch's nodes replaced by their least-squares rigid motion t + θ × d_i, the Euclidean projector onto
// the displacements that move every patch rigidly (it does not depend on the point the motion is written about). With
// d_i from the patch's centroid, Σ d_i = 0 and the normal equations split: n t = Σ u_i, J θ = Σ d_i × u_i with
// J = Σ (|d_i|² I − d_i d_iᵀ), the patch's polar tensor (unit weights).
class RigidProjector {
 public:
  RigidProjector(const RigidPatches& rigid, Eigen::Index dofs) {
    if (rigid.patches.empty()) return;
    if (rigid.nodes == nullptr) throw std::invalid_argument("rigid patches: the node coordinates are missing");
    const Eigen::Index nodes = rigid.nodes->rows();
    if (3 * nodes != dofs) throw std::invalid_argument("rigid patches: their mesh and the stiffness differ in size");
    std::vector<char> taken(static_cast<std::size_t>(nodes), 0);  // Π is a projector only for disjoint patches
    for (const RigidInterface& patch : rigid.patches) {
      Patch p;
      p.nodes = patch.nodes;
      if (p.nodes.size() == 0) throw std::invalid_argument("rigid patch: no nodes");
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (Eigen::Index a = 0; a < p.nodes.size(); ++a) {
        const Eigen::Index i = p.nodes(a);
        if (i < 0 || i >= nodes) throw std::invalid_argument("rigid patch: a node index is out of range");
        if (taken[static_cast<std::size_t>(i)]++) throw std::invalid_argument("rigid patches: a node is in two of them (or twice in one)");
        centroid += rigid.nodes->row(i).transpose();
      }
      centroid /= static_cast<double>(p.nodes.size());
      p.offsets.resize(3, p.nodes.size());
      Eigen::Matrix3d polar = Eigen::Matrix3d::Zero();
      for (Eigen::Index a = 0; a < p.nodes.size(); ++a) {
        const Eigen::Vector3d d = rigid.nodes->row(p.nodes(a)).transpose() - centroid;
        p.offsets.col(a) = d;
        polar += d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose();
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> spectrum(polar);
      if (!(spectrum.eigenvalues()(0) > 1e-10 * spectrum.eigenvalues()(2)))
        throw std::invalid_argument("rigid patch: its nodes lie on a line, so its rotation about that line is not fixed");
      p.polar = polar.ldlt();
      patches_.push_back(std::move(p));
    }
  }
  [[nodiscard]] bool empty() const { return patches_.empty(); }
  /// With the known fields W (M̄-orthonormal, rigid on every patch): Q, the Euclidean projector onto V = {Π u = u,
  /// Wᵀ M̄ u = 0}, is Π less its part along U = Π M̄ W: Q x = Π x − U (UᵀU)⁻¹ Uᵀ Π x.
  void set_known(const Eigen::MatrixXd& known, const SparseMatrix& scalar_mass_upper) {
    along_.resize(known.rows(), known.cols());
    for (Eigen::Index k = 0; k < known.cols(); ++k) {
      apply_vector_mass(scalar_mass_upper, known.col(k), along_.col(k));
      apply(along_.col(k));
    }
    gram_ = (along_.transpose() * along_).ldlt();
    // WᵀU = Wᵀ M̄ W = I: UᵀU is positive definite whenever W is M̄-orthonormal and rigid on the patches.
    if (gram_.info() != Eigen::Success || !(gram_.vectorD().minCoeff() > 0.0))
      throw std::invalid_argument("rigid patches: the known fields do not move the patches rigidly");
  }
  /// x ← Q x: a displacement into V, or a force to the one that represents it on V (Galerkin: vᵀ f for v in V).
  void constrain(Eigen::Ref<Eigen::VectorXd> x) const {
    apply(x);
    if (along_.cols() > 0) x -= along_ * gram_.solve(along_.transpose() * x);
  }
  void apply(Eigen::Ref<Eigen::VectorXd> x) const {
    for (const Patch& p : patches_) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
      for (Eigen::Index a = 0; a < p.nodes.size(); ++a) {
        const Eigen::Vector3d u = x.segment<3>(3 * p.nodes(a));
        sum += u;
        moment += p.offsets.col(a).cross(u);
      }
      const Eigen::Vector3d t = sum / static_cast<double>(p.nodes.size()), theta = p.polar.solve(moment);
      for (Eigen::Index a = 0; a < p.nodes.size(); ++a) x.segment<3>(3 * p.nodes(a)) = t + theta.cross(p.offsets.col(a));
    }
  }

 private:
  struct Patch {
    Eigen::VectorXi nodes;
    Eigen::Matrix3Xd offsets;  ///< from the patch's centroid
    Eigen::LDLT<Eigen::Matrix3d> polar;
  };
  std::vector<Patch> patches_;
  Eigen::MatrixXd along_;  ///< U = Π M̄ W
  Eigen::LDLT<Eigen::MatrixXd> gram_;
};

}  // namespace

Eigen::MatrixXd unit_load_vectors(const RowMatrixX3d& nodes, const std::vector<LoadPoint>& points) {
  Eigen::Index columns = 0;
  for (const LoadPoint& p : points) {
    int count = 0;
    for (bool on : p.loads) count += on;
    if (count == 0) throw std::invalid_argument(fmt::format("load point '{}': no unit load selected", p.name));
    if (p.nodes.size() == 0 || p.nodes.size() != p.weights.size())
      throw std::invalid_argument(fmt::format("load point '{}': no nodes, or not one weight per node", p.name));
    columns += count;
  }
  Eigen::MatrixXd loads = Eigen::MatrixXd::Zero(3 * nodes.rows(), columns);
  Eigen::Index column = 0;
  for (const LoadPoint& p : points) {
    // The rbe3 distribution has zero net force and the unit moment only about the weighted centroid.
    Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();
    double size = 0.0;
    for (Eigen::Index a = 0; a < p.nodes.size(); ++a) {
      const Eigen::Vector3d d = nodes.row(p.nodes(a)).transpose() - p.reference_point;
      first_moment += p.weights(a) * d;
      size = std::max(size, d.norm());
    }
    // The centroid's own rounding is about ε |c|: a small patch far from the centre of mass (an interface of a
    // 1 km part) needs that in the tolerance (117 of 200 random patches at 5000 sizes away failed).
    if (std::abs(p.weights.sum() - 1.0) > 1e-12 || first_moment.norm() > 1e-12 * (size + p.reference_point.norm()))
      throw std::invalid_argument(fmt::format("load point '{}': the weights must sum to 1 and the reference point "
                                              "must be their weighted centroid", p.name));
    Eigen::Matrix3d polar = Eigen::Matrix3d::Zero();  // J = Σ w_i (|d_i|² I − d_i d_iᵀ)
    for (Eigen::Index a = 0; a < p.nodes.size(); ++a) {
      const Eigen::Vector3d d = nodes.row(p.nodes(a)).transpose() - p.reference_point;
      polar += p.weights(a) * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
    }
    const bool moments = p.loads[3] || p.loads[4] || p.loads[5];
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> spectrum(polar);
    if (moments && !(spectrum.eigenvalues()(0) > 1e-10 * spectrum.eigenvalues()(2)))
      throw std::invalid_argument(fmt::format("load point '{}': its nodes lie on a line, so a moment about that line "
                                              "cannot be distributed over them", p.name));
    const Eigen::Matrix3d polar_inverse = moments ? Eigen::Matrix3d(polar.inverse()) : Eigen::Matrix3d::Zero();
    for (int k = 0; k < 6; ++k) {
      if (!p.loads[static_cast<std::size_t>(k)]) continue;
      for (Eigen::Index a = 0; a < p.nodes.size(); ++a) {
        const Eigen::Index i = p.nodes(a);
        const Eigen::Vector3d d = nodes.row(i).transpose() - p.reference_point;
        loads.block<3, 1>(3 * i, column) = k < 3 ? Eigen::Vector3d(p.weights(a) * Eigen::Vector3d::Unit(k))
                                                 : Eigen::Vector3d(p.weights(a) * (polar_inverse.col(k - 3)).cross(d));
      }
      ++column;
    }
  }
  return loads;
}

std::vector<std::string> unit_load_labels(const std::vector<LoadPoint>& points) {
  std::vector<std::string> labels;
  for (const LoadPoint& p : points)
    for (std::size_t k = 0; k < 6; ++k)
      if (p.loads[k]) labels.push_back(p.name + ":" + kUnitLoadNames[k]);
  return labels;
}

namespace {

// One batch of relieved_static_responses' loads (the columns of `loads`); `name(c)` names load c in errors.
Eigen::MatrixXd relieved_batch(ShiftSolve& solve, const SparseMatrix& stiffness_upper,
                               const SparseMatrix& scalar_mass_upper, const Eigen::MatrixXd& known,
                               const Eigen::MatrixXd& loads, StaticCorrectionStats& stats,
                               const std::function<std::string(Eigen::Index)>& name, const RigidProjector& rigid) {
  const Eigen::Index n = stiffness_upper.rows();
  const Eigen::Index s = loads.cols();
  // Preconditioned conjugate gradients on PᵀK̄P u = Pᵀ f, one iteration per load (column), the loads in lockstep: the
  // preconditioner serves every load still iterating in one block solve (one pass over the factor: CHOLMOD's block
  // solve), which took 144 single solves of 24 loads on the quadratic bracket before.
  Eigen::MatrixXd responses = Eigen::MatrixXd::Zero(n, s), b = loads, r(n, s), z(n, s), p(n, s);
  Eigen::VectorXd b_norm(s), rz(s), q(n), magnitude(n);
  std::vector<Eigen::Index> pending;  // loads to solve (again, in the second pass)
  // Forces and displacements on the M̄-complement of the known fields: Pᵀ f and P u (inertia relief). With rigid
  // patches, on V = {u moving each patch rigidly, Wᵀ M̄ u = 0} instead: Q f and Q u (Galerkin on V: the relief and the
  // patches' constraint forces are what Q removes), the preconditioner Q (K̄ − σM̄)⁻¹ Q.
  auto as_force = [&](Eigen::Ref<Eigen::VectorXd> x) {
    if (rigid.empty()) project_force(known, scalar_mass_upper, x);
    else rigid.constrain(x);
  };
  auto as_displacement = [&](Eigen::Ref<Eigen::VectorXd> x) {
    if (rigid.empty()) project(known, scalar_mass_upper, x);
    else rigid.constrain(x);
  };
  for (Eigen::Index c = 0; c < s; ++c) {
    as_force(b.col(c));
    b_norm(c) = b.col(c).norm();
    // Else wholly in the known fields (or, with rigid patches, self-equilibrated on a patch): no response.
    if (b_norm(c) > 1e-14 * loads.col(c).norm()) pending.push_back(c);
  }
  Eigen::MatrixXd block_in, block_out;
  auto precondition = [&](const std::vector<Eigen::Index>& columns) {  // z = P (K̄ − σM̄)⁻¹ r for these columns
    const auto count = static_cast<Eigen::Index>(columns.size());
    block_in.resize(n, count);
    block_out.resize(n, count);
    for (Eigen::Index j = 0; j < count; ++j) block_in.col(j) = r.col(columns[static_cast<std::size_t>(j)]);
    solve.perform_block(block_in.data(), block_out.data(), count);
    for (Eigen::Index j = 0; j < count; ++j) {
      const Eigen::Index c = columns[static_cast<std::size_t>(j)];
      z.col(c) = block_out.col(j);
      as_displacement(z.col(c));
    }
  };
  for (int pass = 0; pass < 2 && !pending.empty(); ++pass) {  // a second pass restarts from u with the true residual
    for (const Eigen::Index c : pending) {
      apply_symmetric(stiffness_upper, responses.col(c), q);
      as_force(q);
      r.col(c) = b.col(c) - q;
    }
    std::vector<Eigen::Index> active;
    for (const Eigen::Index c : pending)
      if (r.col(c).norm() > kSolveTolerance * b_norm(c)) active.push_back(c);
    if (!active.empty()) precondition(active);
    for (const Eigen::Index c : active) {
      p.col(c) = z.col(c);
      rz(c) = r.col(c).dot(z.col(c));
    }
    for (int iteration = 0; !active.empty(); ++iteration) {
      if (iteration == kMaxIterations)
        throw std::runtime_error(fmt::format("{} did not converge in {} iterations (residual {:.3g})",
                                             name(active.front()), kMaxIterations,
                                             r.col(active.front()).norm() / b_norm(active.front())));
      std::vector<Eigen::Index> still;
      for (const Eigen::Index c : active) {
        if (!(rz(c) > 0.0))
          throw std::runtime_error(fmt::format("{}: the preconditioner is not positive definite", name(c)));
        ++stats.iterations;
        apply_symmetric(stiffness_upper, p.col(c), q);
        as_force(q);
        const double pq = p.col(c).dot(q);
        if (!(pq > 0.0))
          throw std::runtime_error(fmt::format("{}: the stiffness is not positive on the complement of the known "
                                               "fields (a zero-energy mode missing?)", name(c)));
        const double alpha = rz(c) / pq;
        responses.col(c) += alpha * p.col(c);
        r.col(c) -= alpha * q;
        if (r.col(c).norm() > kSolveTolerance * b_norm(c)) still.push_back(c);
      }
      active = std::move(still);
      if (active.empty()) break;
      precondition(active);
      for (const Eigen::Index c : active) {
        const double rz_next = r.col(c).dot(z.col(c));
        p.col(c) = z.col(c) + (rz_next / rz(c)) * p.col(c);
        rz(c) = rz_next;
      }
    }
    std::vector<Eigen::Index> failed;
    for (const Eigen::Index c : pending) {  // the true residual (the recursive one can drift from it)
      apply_symmetric_with_magnitude(stiffness_upper, responses.col(c), q, magnitude);
      as_force(q);
      const double true_residual = (b.col(c) - q).norm() / b_norm(c);
      const double floor = DBL_EPSILON * magnitude.norm() / b_norm(c);
      if (!(true_residual <= accepted_residual(floor))) {
        if (pass == 1)
          throw std::runtime_error(fmt::format("{}: not converged: {}", name(c), describe_refusal(true_residual, floor)));
        failed.push_back(c);
        continue;
      }
      stats.max_relative_residual = std::max(stats.max_relative_residual, true_residual);
      stats.max_residual_to_floor = std::max(stats.max_residual_to_floor, true_residual / floor);
    }
    pending = std::move(failed);
  }
  return responses;
}

}  // namespace

Eigen::MatrixXd relieved_static_responses(ShiftSolve& solve, const SparseMatrix& stiffness_upper,
                                          const SparseMatrix& scalar_mass_upper, const Eigen::MatrixXd& known,
                                          const Eigen::MatrixXd& loads, StaticCorrectionStats& stats,
                                          const std::vector<std::string>& names, std::string_view what,
                                          const RigidPatches& rigid_patches) {
  const Eigen::Index n = stiffness_upper.rows(), s = loads.cols();
  const std::string prefix(what);
  if (solve.rows() != n || scalar_mass_upper.rows() * 3 != n || known.rows() != n || loads.rows() != n)
    throw std::invalid_argument(prefix + ": the factorization, K, M, the known fields and the loads differ in size");
  if (!names.empty() && static_cast<Eigen::Index>(names.size()) != s)
    throw std::invalid_argument(prefix + ": the loads and their names differ in number");
  if (!loads.allFinite()) throw std::invalid_argument(prefix + ": a load vector is not finite");
  if (solve.shift() > 0.0)
    throw std::invalid_argument(prefix + ": the factorization's shift must be <= 0 (a positive definite preconditioner)");
  stats.loads += s;
  // Batches of kStaticBatch loads: the lockstep holds six n x batch work matrices besides the responses (and
  // CHOLMOD's block solve its own), so a part with many interfaces at 1M DOFs does not need gigabytes for them.
  Eigen::MatrixXd responses(n, s);
  RigidProjector rigid(rigid_patches, n);
  if (!rigid.empty()) rigid.set_known(known, scalar_mass_upper);
  for (Eigen::Index first = 0; first < s; first += kStaticBatch) {
    const Eigen::Index count = std::min(kStaticBatch, s - first);
    auto name = [&](Eigen::Index c) {
      return names.empty() ? fmt::format("{}: load {}", prefix, first + c + 1)
                           : fmt::format("{}: {}", prefix, names[static_cast<std::size_t>(first + c)]);
    };
    responses.middleCols(first, count) = relieved_batch(solve, stiffness_upper, scalar_mass_upper, known,
                                                        loads.middleCols(first, count), stats, name, rigid);
  }
  return responses;
}

StaticCorrectionModes static_correction_modes(ShiftSolve& solve, const SparseMatrix& stiffness_upper,
                                              const SparseMatrix& scalar_mass_upper, const Eigen::MatrixXd& known,
                                              const Eigen::MatrixXd& loads) {
  const Eigen::Index n = stiffness_upper.rows();
  StaticCorrectionModes result;
  const Eigen::Index s = loads.cols();
  result.vectors.resize(n, 0);
  // 1. The residual static responses (inertia relief against the known fields).
  Eigen::MatrixXd responses = relieved_static_responses(solve, stiffness_upper, scalar_mass_upper, known, loads,
                                                        result.stats, {}, "static correction");
  if (s == 0) return result;

  // 2. M̄-orthonormalise the responses, dropping the directions they do not really span.
  Eigen::MatrixXd m_responses(n, s);
  for (Eigen::Index c = 0; c < s; ++c) {
    apply_vector_mass(scalar_mass_upper, responses.col(c), m_responses.col(c));
    const double norm = std::sqrt(std::max(responses.col(c).dot(m_responses.col(c)), 0.0));
    if (norm > 0.0) {
      responses.col(c) /= norm;
      m_responses.col(c) /= norm;
    }
  }
  const Eigen::MatrixXd gram = responses.transpose() * m_responses;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> directions(0.5 * (gram + gram.transpose()));
  const Eigen::VectorXd& d = directions.eigenvalues();  // ascending
  Eigen::Index kept = 0;
  while (kept < s && d(s - 1 - kept) > kDependentGram * std::max(d(s - 1), 1.0)) ++kept;
  result.stats.dropped = s - kept;
  if (kept == 0) return result;
  Eigen::MatrixXd t = responses * directions.eigenvectors().rightCols(kept) *
                      d.tail(kept).cwiseSqrt().cwiseInverse().asDiagonal();
  // Clean the round-off that step 1 left in the known directions, then orthonormalise exactly.
  Eigen::MatrixXd m_t(n, kept), k_t(n, kept);
  for (Eigen::Index c = 0; c < kept; ++c) {
    project(known, scalar_mass_upper, t.col(c));
    apply_vector_mass(scalar_mass_upper, t.col(c), m_t.col(c));
  }
  const Eigen::MatrixXd gram_t = t.transpose() * m_t;
  const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (gram_t + gram_t.transpose()));
  if (llt.info() != Eigen::Success) throw std::runtime_error("static correction: the responses are dependent");
  t = llt.matrixU().solve<Eigen::OnTheRight>(t);

  // 3. Rayleigh-Ritz: diagonalise K̄ on the responses.
  for (Eigen::Index c = 0; c < kept; ++c) apply_symmetric(stiffness_upper, t.col(c), k_t.col(c));
  const Eigen::MatrixXd h = t.transpose() * k_t;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(0.5 * (h + h.transpose()));
  result.vectors = t * ritz.eigenvectors();
  result.eigenvalues = ritz.eigenvalues();
  return result;
}

}  // namespace flexbody::preprocess
