#include "flexbody/preprocess/shift_invert_operator.hpp"

#include "flexbody/preprocess/assembly.hpp"

#include "available_memory.hpp"

#include <cholmod.h>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

namespace flexbody::preprocess {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A cholmod_dense header over caller-owned column-major memory (no copy).
cholmod_dense dense_view(double* data, std::size_t rows, std::size_t cols) {
  cholmod_dense view{};
  view.nrow = rows;
  view.ncol = cols;
  view.nzmax = rows * cols;
  view.d = rows;
  view.x = data;
  view.z = nullptr;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  return view;
}

// CHOLMOD's status codes (Common->status) in words, for the one line a failure prints.
std::string status_text(int status) {
  switch (status) {
    case CHOLMOD_OK: return "no error";
    case CHOLMOD_NOT_INSTALLED: return "a CHOLMOD module it needs is not installed (status -1)";
    case CHOLMOD_OUT_OF_MEMORY: return "out of memory (status -2): use a coarser mesh, linear elements, or MUMPS's "
                                       "out-of-core factor (--eigensolver slepc)";
    case CHOLMOD_TOO_LARGE: return "the problem is too large for CHOLMOD's integer size (status -3)";
    case CHOLMOD_INVALID: return "CHOLMOD was given invalid input (status -4)";
    case CHOLMOD_GPU_PROBLEM: return "a GPU error (status -5)";
    case CHOLMOD_NOT_POSDEF: return "the matrix is not positive definite (status 1)";
    case CHOLMOD_DSMALL: return "a pivot was tiny: the matrix is nearly singular (status 2)";
    default: return "status " + std::to_string(status);
  }
}

}  // namespace

void VectorMassOperator::perform_op(const double* x, double* y) const {
  const Eigen::Index n = rows();
  apply_vector_mass(mass_, Eigen::Map<const Eigen::VectorXd>(x, n), Eigen::Map<Eigen::VectorXd>(y, n));
}

void ShiftSolve::perform_block(const double* x, double* y, Eigen::Index columns) {
  const Eigen::Index n = rows();
  for (Eigen::Index c = 0; c < columns; ++c) perform_op(x + c * n, y + c * n);
}

struct CholmodShiftSolve::Impl {
  const SparseMatrix& stiffness;
  const SparseMatrix& mass;
  Eigen::MatrixXd deflation;       // R, M̄-orthonormal
  Eigen::MatrixXd mass_deflation;  // M̄ R
  std::vector<std::int64_t> mass_positions;  // where each (3i+c, 3j+c) of M̄ sits in K's pattern
  cholmod_common common{};
  cholmod_sparse* matrix = nullptr;
  cholmod_factor* factor = nullptr;
  cholmod_dense* x = nullptr;  // solve2 workspaces, reused between solves
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;

  Impl(const SparseMatrix& k, const SparseMatrix& m) : stiffness(k), mass(m) {
    cholmod_l_start(&common);
    common.print = 0;
    common.supernodal = CHOLMOD_SUPERNODAL;
  }
  ~Impl() {
    cholmod_l_free_dense(&x, &common);
    cholmod_l_free_dense(&y, &common);
    cholmod_l_free_dense(&e, &common);
    cholmod_l_free_factor(&factor, &common);
    cholmod_l_free_sparse(&matrix, &common);
    cholmod_l_finish(&common);
  }

  // Symbolic analysis of K̄ - sigma M̄ with a fill-reducing ordering of the node graph expanded to each
  // node's three DOFs. Ordering the DOF graph instead, with 9x the entries, made the analysis 2.1-3.0 s
  // against 1.1-1.7 s at 193k DOFs, for the same fill. Both AMD and METIS are tried, always, and the one
  // with less fill kept: CHOLMOD's default skips METIS when AMD's flops per entry of L are below 500, and
  // on the node graph that ratio is about a third of the DOF graph's, so METIS could be skipped where it wins.
  cholmod_factor* analyze_by_nodes() {
    // The node graph from K's pattern (not M_s's: a lumped mass is diagonal): node i <= j is a neighbour
    // of node j if K has a stored entry in DOF column 3j + 2, which holds every row of the 3x3 blocks.
    const auto n_nodes = static_cast<std::size_t>(mass.rows());
    std::vector<std::int64_t> node_start(n_nodes + 1, 0), node_rows;
    node_rows.reserve(static_cast<std::size_t>(stiffness.nonZeros()) / 9 + n_nodes);
    for (std::size_t j = 0; j < n_nodes; ++j) {
      const auto column = static_cast<Eigen::Index>(3 * j + 2);
      for (SparseMatrix::InnerIterator it(stiffness, column); it; ++it)
        if (node_rows.size() == static_cast<std::size_t>(node_start[j]) || node_rows.back() != it.row() / 3)
          node_rows.push_back(it.row() / 3);
      node_start[j + 1] = static_cast<std::int64_t>(node_rows.size());
    }
    cholmod_sparse pattern{};
    pattern.nrow = pattern.ncol = n_nodes;
    pattern.nzmax = node_rows.size();
    pattern.p = node_start.data();
    pattern.i = node_rows.data();
    pattern.stype = 1;
    pattern.itype = CHOLMOD_LONG;
    pattern.xtype = CHOLMOD_PATTERN;
    pattern.dtype = CHOLMOD_DOUBLE;
    pattern.sorted = 1;
    pattern.packed = 1;
    std::vector<std::int64_t> dof_order(3 * n_nodes);
    const int saved_methods = common.nmethods;
    const int saved_orderings[2] = {common.method[0].ordering, common.method[1].ordering};
    common.supernodal = CHOLMOD_SIMPLICIAL;  // only the ordering is wanted here
    common.nmethods = 2;
    common.method[0].ordering = CHOLMOD_AMD;
    common.method[1].ordering = CHOLMOD_METIS;
    cholmod_factor* nodes = cholmod_l_analyze(&pattern, &common);
    common.supernodal = CHOLMOD_SUPERNODAL;
    cholmod_factor* dofs = nullptr;
    if (nodes != nullptr) {
      const auto* node_order = static_cast<const std::int64_t*>(nodes->Perm);
      for (std::size_t k = 0; k < n_nodes; ++k)
        for (int c = 0; c < 3; ++c) dof_order[3 * k + c] = 3 * node_order[k] + c;
      cholmod_l_free_factor(&nodes, &common);
      common.nmethods = 1;
      common.method[0].ordering = CHOLMOD_GIVEN;  // CHOLMOD still postorders it
      dofs = cholmod_l_analyze_p(matrix, dof_order.data(), nullptr, 0, &common);
    }
    common.nmethods = saved_methods;
    common.method[0].ordering = saved_orderings[0];
    common.method[1].ordering = saved_orderings[1];
    return dofs;
  }

  void locate_mass_entries() {
    mass_positions.reserve(3 * static_cast<std::size_t>(mass.nonZeros()));
    const std::int64_t* col = stiffness.outerIndexPtr();
    const std::int64_t* row = stiffness.innerIndexPtr();
    for (Eigen::Index j = 0; j < mass.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(mass, j); it; ++it)
        for (int c = 0; c < 3; ++c) {
          const std::int64_t target_col = 3 * j + c;
          const std::int64_t target_row = 3 * it.row() + c;
          const std::int64_t* first = row + col[target_col];
          const std::int64_t* last = row + col[target_col + 1];
          const std::int64_t* found = std::lower_bound(first, last, target_row);
          if (found == last || *found != target_row)
            throw std::logic_error("shift-invert: the mass pattern is not contained in the stiffness pattern");
          mass_positions.push_back(found - row);
        }
  }
};

CholmodShiftSolve::CholmodShiftSolve(const SparseMatrix& stiffness_upper, const SparseMatrix& scalar_mass_upper,
                                     Eigen::MatrixXd deflation, std::optional<std::uint64_t> memory_bytes)
    : impl_(std::make_unique<Impl>(stiffness_upper, scalar_mass_upper)) {
  if (stiffness_upper.rows() != 3 * scalar_mass_upper.rows() || !stiffness_upper.isCompressed() ||
      !scalar_mass_upper.isCompressed())
    throw std::logic_error("shift-invert: K must be 3 n_n square and both matrices compressed");
  impl_->deflation = std::move(deflation);
  impl_->mass_deflation.resize(impl_->deflation.rows(), impl_->deflation.cols());
  for (Eigen::Index k = 0; k < impl_->deflation.cols(); ++k)
    apply_vector_mass(scalar_mass_upper, impl_->deflation.col(k), impl_->mass_deflation.col(k));
  impl_->locate_mass_entries();

  const auto n = static_cast<std::size_t>(stiffness_upper.rows());
  const auto nnz = static_cast<std::size_t>(stiffness_upper.nonZeros());
  impl_->matrix = cholmod_l_allocate_sparse(n, n, nnz, /*sorted=*/1, /*packed=*/1, /*stype=*/1, CHOLMOD_REAL,
                                            &impl_->common);
  if (impl_->matrix == nullptr) throw std::runtime_error("shift-invert: out of memory for K - sigma M");
  std::copy_n(stiffness_upper.outerIndexPtr(), n + 1, static_cast<std::int64_t*>(impl_->matrix->p));
  std::copy_n(stiffness_upper.innerIndexPtr(), nnz, static_cast<std::int64_t*>(impl_->matrix->i));

  const auto start = std::chrono::steady_clock::now();
  impl_->factor = impl_->analyze_by_nodes();
  if (impl_->factor == nullptr)
    throw std::runtime_error("shift-invert: CHOLMOD's analysis of K - sigma M failed: " +
                             status_text(impl_->common.status));
  stats_.analyze_seconds = seconds_since(start);
  // What the numeric factorization will allocate, known before it (the analysis is supernodal: common.supernodal):
  // the factor's values (xsize), the largest update matrix it works in (maxcsize), and the permuted copy of the
  // matrix it factorizes (cholmod_factorize's ptranspose: a value and a row index per entry, and the column
  // pointers); 8 bytes each. The supernodes' structure (ssize) is already allocated by the analysis.
  const cholmod_factor& l = *impl_->factor;
  const double bytes = 8.0 * (static_cast<double>(l.xsize) + static_cast<double>(l.maxcsize) +
                              2.0 * static_cast<double>(nnz) + static_cast<double>(n + 1));
  stats_.factor_estimate_megabytes = bytes * 1e-6;
  const std::optional<std::uint64_t> room = memory_bytes ? memory_bytes : detail::available_memory_bytes();
  if (room && bytes > static_cast<double>(*room))
    throw std::runtime_error(fmt::format(
        "shift-invert: the factor of K - sigma M ({} rows, {:.3g} entries after ordering) would need about {:.3g} GB, "
        "more than the {:.3g} GB {}; use a coarser mesh (--mesh-size), linear elements (--order 1) if they are "
        "quadratic, or MUMPS's out-of-core factor (--eigensolver slepc in a build with FLEXBODY_WITH_SLEPC; "
        "docs/eigensolvers.md: \"On Several Processes\")",
        n, impl_->common.lnz, bytes * 1e-9, static_cast<double>(*room) * 1e-9,
        memory_bytes ? "allowed" : "this process can still take"));
}

CholmodShiftSolve::~CholmodShiftSolve() = default;

static_assert(ShiftSolveOperator<CholmodShiftSolve>);
static_assert(MassOperator<VectorMassOperator>);

Eigen::Index CholmodShiftSolve::rows() const { return impl_->stiffness.rows(); }

void CholmodShiftSolve::set_shift(double sigma) {
  sigma_ = sigma;
  auto* values = static_cast<double*>(impl_->matrix->x);
  std::copy_n(impl_->stiffness.valuePtr(), impl_->stiffness.nonZeros(), values);
  std::size_t next = 0;
  const double* mass_values = impl_->mass.valuePtr();
  for (Eigen::Index k = 0; k < impl_->mass.nonZeros(); ++k)
    for (int c = 0; c < 3; ++c) values[impl_->mass_positions[next++]] -= sigma * mass_values[k];

  const auto start = std::chrono::steady_clock::now();
  const int ok = cholmod_l_factorize(impl_->matrix, impl_->factor, &impl_->common);
  stats_.factorize_seconds += seconds_since(start);
  if (!ok || impl_->common.status != CHOLMOD_OK)
    throw std::runtime_error(impl_->common.status == CHOLMOD_NOT_POSDEF
                                 ? fmt::format("shift-invert: K - sigma M is not positive definite at sigma = {:.6g}", sigma) +
                                       " (column " +
                                       std::to_string(impl_->factor->minor) + ")"
                                 : "shift-invert: CHOLMOD's factorization of K - sigma M failed: " +
                                       status_text(impl_->common.status));
  stats_.factor_nonzeros = impl_->common.lnz;
  stats_.factor_flops = impl_->common.fl;
}

void CholmodShiftSolve::perform_op(const double* x, double* y) { perform_block(x, y, 1); }

void CholmodShiftSolve::perform_block(const double* x, double* y, Eigen::Index columns) {
  const auto n = static_cast<std::size_t>(rows());
  cholmod_dense rhs = dense_view(const_cast<double*>(x), n, static_cast<std::size_t>(columns));
  const auto start = std::chrono::steady_clock::now();
  if (!cholmod_l_solve2(CHOLMOD_A, impl_->factor, &rhs, nullptr, &impl_->x, nullptr, &impl_->y, &impl_->e,
                        &impl_->common))
    throw std::runtime_error("shift-invert: CHOLMOD's solve failed: " + status_text(impl_->common.status));
  stats_.solve_seconds += seconds_since(start);
  stats_.solves += columns;
  ++stats_.solve_passes;
  Eigen::Map<Eigen::MatrixXd> result(y, static_cast<Eigen::Index>(n), columns);
  result = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(impl_->x->x), static_cast<Eigen::Index>(n),
                                             columns);
  if (impl_->deflation.cols() > 0)  // Y <- Y - R (M̄ R)ᵀ Y
    result.noalias() -= impl_->deflation * (impl_->mass_deflation.transpose() * result);
}

}  // namespace flexbody::preprocess
