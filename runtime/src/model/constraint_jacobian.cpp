// System::Impl::sparse_constraint_jacobian: Φ_q block by block, each block over the coordinates of the bodies its rows
// touch (formulations.md, "The Method": constraints and markers), so its storage grows with the scene, not with its
// square.
#include "flexbody/runtime/reference_constraints.hpp"
#include "system_impl.hpp"

#include "../kernels/parallel.hpp"
#include "../kernels/triplet_assembly.hpp"

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseQR>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace flexbody::runtime {

void System::Impl::sparse_constraint_jacobian(double t, const Eigen::VectorXd& q,
                                              Eigen::SparseMatrix<double>& out) const {
  std::vector<Eigen::Triplet<double>>& entries = jacobian_work_;  // kept: its storage is reused
  entries.clear();
  auto add_block = [&entries](Eigen::Index row, Eigen::Index column, const Eigen::Ref<const Eigen::MatrixXd>& block) {
    for (Eigen::Index c = 0; c < block.cols(); ++c)
      for (Eigen::Index r = 0; r < block.rows(); ++r) entries.emplace_back(row + r, column + c, block(r, c));
  };
  Eigen::Index row = 0;
  for (const Body& b : bodies_) {
    const Eigen::Index n = b.model.coordinate_count();
    const auto q_b = q.segment(b.offset, n);
    if (b.model.floating()) {  // pᵀp − 1 = 0
      add_block(row++, b.offset + 3, 2.0 * q_b.segment<4>(3).transpose());
      continue;
    }
    // Eq. 79 (orthogonality) over a, Eq. 78 (rotational Tisserand) over [a; ξ].
    const Eigen::MatrixXd reference = reference_jacobian(b.model.tisserand, orientation_of(q_b), q_b.tail(n - 12));
    add_block(row, b.offset + 3, reference.topLeftCorner(6, 9));
    if (reference_rows(b) >= 9) add_block(row + 6, b.offset + 3, reference.middleRows(6, 3));
    if (reference_rows(b) == 12)  // Eq. 77: Σ_f G[0, 4 + f] ξ_f, diagonal 3-blocks
      for (Eigen::Index f = 0; f < b.model.field_count(); ++f)
        for (int d = 0; d < 3; ++d) entries.emplace_back(row + 9 + d, b.offset + 12 + 3 * f + d, b.model.g_border(0, 4 + f));
    row += reference_rows(b);
  }
  const auto count = static_cast<int>(joints_.size());
  detail::for_each(count, [&](int k) { evaluated(static_cast<std::size_t>(k), t, q); });  // each its own storage
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const Joint& j = joints_[k];
    const JointEvaluation& e = joint_work_[k];
    // Both markers on one body: their blocks add up (setFromTriplets sums duplicates).
    if (j.first.body != kGround) add_block(row, offset(j.first.body), e.jacobian_first);
    if (j.second.body != kGround) add_block(row, offset(j.second.body), e.jacobian_second);
    row += j.rows();
  }
  if (!jacobian_assembly_.ptr) jacobian_assembly_.ptr = std::make_shared<detail::TripletAssembly>();
  jacobian_assembly_.ptr->assemble(constraint_count(), coordinates_, entries, out);
}

namespace {

// The rows of Φ_q that are linearly dependent on the rows before them, in row order (empty: independent rows).
// Each row normalised (rows carry different units: m, rad, kg^½ m), then Householder QR of Φ_qᵀ with the columns
// (the rows of Φ_q) in their order: a column whose remainder after the ones before it is below 1e-9 of its length
// adds nothing (the Gram-Schmidt test, with Householder's accuracy), and SparseQR moves it behind the others. The
// fill is that of a Cholesky factor of Φ_q Φ_qᵀ in row order: each joint's rows touch two bodies, so it stays
// linear in a chain or a ladder of loops, where the dense Gram-Schmidt this replaces cost O(m² n).
std::vector<Eigen::Index> dependent_rows(const Eigen::SparseMatrix<double>& jac) {
  Eigen::VectorXd length = Eigen::VectorXd::Zero(jac.rows());
  for (Eigen::Index k = 0; k < jac.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(jac, k); it; ++it) length(it.row()) += it.value() * it.value();
  std::vector<Eigen::Index> dependent;
  bool empty_rows = false;  // a row that constrains nothing: dependent, and the QR below finds the others too
  for (Eigen::Index k = 0; k < jac.rows(); ++k) {
    if (length(k) > 0.0) {
      length(k) = 1.0 / std::sqrt(length(k));
    } else {
      length(k) = 1.0;
      empty_rows = true;
    }
  }
  Eigen::SparseMatrix<double> rows = (length.asDiagonal() * jac).transpose();  // n x m, column k = row k / |row k|
  rows.makeCompressed();
  // First whether any row is dependent at all, cheaply: the LDLᵀ of the rows' Gram matrix (unit diagonal) in row
  // order. Its pivots are the squared remainders of the rows after the ones before them, the QR's test below, up to
  // rounding that grows with the Gram matrix's condition (an exactly dependent row of a random mechanism left a pivot
  // of 1.3e-12, sparse_newton_test). All above 1e-6 (remainders above 1e-3 of a row's length) means independent rows,
  // beyond doubt; otherwise the QR below decides, and finds the dependent rows in row order (slower: its fill grows
  // with the scene's width; the dense Gram-Schmidt it replaces cost O(m² n) in every scene). In row order, a chain's
  // pivots stay at 0.5 whatever its length (each joint brings a body not seen before); a fill-reducing order (AMD)
  // left pivots falling like N^-2.5 (2.5e-5 at 256 rigid links), so that from about 700 links the test failed and the
  // QR ran: 61 s to set up 1024 links in Euler parameters. Row order can fill where a fill-reducing order would not:
  // a large tree whose joints are listed breadth first makes a frontier as wide as a generation (a scene listed
  // depth first, or by chains, does not).
  if (!empty_rows) {
    const Eigen::SparseMatrix<double> gram = rows.transpose() * rows;
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> ldlt(gram);
    if (ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 1e-6) return dependent;
  }
  Eigen::SparseQR<Eigen::SparseMatrix<double>, Eigen::NaturalOrdering<int>> qr;
  qr.setPivotThreshold(1e-9);
  qr.compute(rows);
  if (qr.info() != Eigen::Success) throw std::runtime_error("the constraint rows' QR factorization failed");
  const auto& order = qr.colsPermutation().indices();  // the independent columns first, then the dependent ones
  dependent.assign(order.data() + qr.rank(), order.data() + order.size());
  std::sort(dependent.begin(), dependent.end());
  return dependent;
}

}  // namespace

Eigen::Index System::Impl::first_redundant_constraint(double t, const Eigen::VectorXd& q) const {
  Eigen::SparseMatrix<double> jac;
  sparse_constraint_jacobian(t, q, jac);
  const std::vector<Eigen::Index> dependent = dependent_rows(jac);
  return dependent.empty() ? -1 : dependent.front();
}

std::vector<RemovedConstraint> System::Impl::remove_redundant_constraints(double t, const Eigen::VectorXd& q) {
  if (q.size() != coordinates_) throw std::invalid_argument("remove_redundant_constraints: q has the wrong size");
  Eigen::SparseMatrix<double> jac;
  sparse_constraint_jacobian(t, q, jac);
  const std::vector<Eigen::Index> dependent = dependent_rows(jac);
  if (!dependent.empty() && dependent.front() < reference_total_)  // a degenerate body file, not a scene's choice
    throw std::invalid_argument(constraint_name(dependent.front()) + " is degenerate: the body's own rows are linearly "
                                "dependent");
  // Each dependent row to its joint and to the joint type's row (counting the rows removed before), all decided
  // before any joint changes, since the rows' numbering changes with each removal.
  std::vector<RemovedConstraint> removed;
  std::vector<unsigned> masks(joints_.size());
  for (std::size_t k = 0; k < joints_.size(); ++k) masks[k] = joints_[k].removed;
  for (const Eigen::Index row : dependent) {
    std::size_t k = 0;
    while (k + 1 < joints_.size() && joint_row(k + 1) <= row) ++k;
    const Joint& j = joints_[k];
    int kept = static_cast<int>(row - joint_row(k)), type_row = 0;  // the kept-th kept row of the type's rows
    for (;; ++type_row)
      if (!((j.removed >> type_row) & 1U) && kept-- == 0) break;
    if (j.type == JointType::driven_revolute && type_row == j.type_rows() - 1)  // leaving it out would drop the drive
      throw std::invalid_argument("joint '" + j.name + "': its driven angle is redundant: the constraints before it "
                                  "already hold that rotation, so the drive cannot act");
    masks[k] |= 1U << type_row;
    const Eigen::VectorXd q1 = body_coordinates(q, j.first.body), q2 = body_coordinates(q, j.second.body);
    removed.push_back({k, j.name, type_row, joint_row_meaning(j, type_row, q1, q2),
                       std::abs(joint_type_residuals(j, t, q1, q2)(type_row))});
  }
  joint_total_ = 0;
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    joints_[k].removed = masks[k];
    joint_start_[k] = joint_total_;
    joint_total_ += joints_[k].rows();
  }
  return removed;
}

}  // namespace flexbody::runtime
