#pragma once
// saddle_point.hpp (internal): the start of a run solves K [x; λ] = [r; b] with K = [M Φ_qᵀ; Φ_q 0] twice (consistent
// velocities, initial accelerations). M is block diagonal and, for a full-order body, of a mesh's size and sparsity.
//
// A sparse LU of K took 10 s of a 13 s run at 10k DOFs (perf: 76 % in SparseLU::factorize; the mesh's fill under
// COLAMD). So the mesh-sized part is eliminated first: the full-order bodies' field coordinates F, whose block
// M_FF = M_s ⊗ I3 is SPD and sparse (Cholesky), leave a reduced system in the other coordinates and the multipliers,
//   (K_RR − K_RF M_FF⁻¹ K_FR) y = r_R − K_RF M_FF⁻¹ r_F,   M_FF x_F = r_F − K_FR y,
// in which K_FR has few columns that are not zero (the body's 12 rigid coordinates and the constraint rows that touch
// its nodes: its Tisserand rows and its joints'), one sparse solve each. The reduced system keeps K's other blocks
// and goes to the sparse LU, which is what the whole K did before in a scene without full-order bodies.

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

#include <vector>

namespace flexbody::runtime::detail {

class SaddlePointSolver {
 public:
  /// K from M (n square, symmetric, both triangles) and the m x n rows Φ_q; `eliminated` (n) marks F, whose block of M
  /// must be SPD. ok() is false when the reduced system is singular (redundant rows, or a body whose mass is singular
  /// where no row holds it): the caller names the cause.
  SaddlePointSolver(const Eigen::SparseMatrix<double>& mass, const Eigen::SparseMatrix<double>& jacobian,
                    const std::vector<bool>& eliminated);

  [[nodiscard]] bool ok() const { return ok_; }
  /// [x; λ] for the right-hand side [r; b] (n + m).
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const;

 private:
  std::vector<Eigen::Index> f_, y_;  ///< K's indices of F, and of the rest (coordinates, then multipliers)
  std::vector<Eigen::Index> coupled_;  ///< the positions in y of K_FR's nonzero columns
  Eigen::SparseMatrix<double> coupling_;  ///< K_FR restricted to those columns (|F| x |coupled|)
  Eigen::MatrixXd solved_coupling_;       ///< M_FF⁻¹ K_FR on them
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> block_;  ///< M_FF
  Eigen::SparseLU<Eigen::SparseMatrix<double>> reduced_;    ///< K_RR − K_RF M_FF⁻¹ K_FR
  bool ok_ = false;
};

}  // namespace flexbody::runtime::detail
