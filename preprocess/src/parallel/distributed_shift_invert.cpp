#include "distributed_shift_invert.hpp"

#include "petsc_runtime.hpp"

#include <petscmat.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <utility>

namespace flexbody::preprocess::parallel {
namespace {

using FullRows = Eigen::SparseMatrix<double, Eigen::RowMajor, std::int64_t>;

// The first node of rank q: whole nodes (three rows each), as evenly as possible.
PetscInt first_node(PetscInt n_nodes, int q, int ranks) {
  return n_nodes / ranks * q + std::min<PetscInt>(q, n_nodes % ranks);
}

// One rank's rows in PETSc's CSR form: local row starts, global column indices.
struct RowBlock {
  std::vector<PetscInt> start{0};
  std::vector<PetscInt> columns;
  std::vector<PetscScalar> values;
};

// Rows [first, end) of a full symmetric matrix.
RowBlock block_of(const FullRows& full, Eigen::Index first, Eigen::Index end) {
  RowBlock block;
  const std::int64_t* outer = full.outerIndexPtr();
  const std::size_t entries = static_cast<std::size_t>(outer[end] - outer[first]);
  block.columns.reserve(entries);
  block.values.assign(full.valuePtr() + outer[first], full.valuePtr() + outer[end]);
  for (Eigen::Index i = first; i < end; ++i) {
    for (std::int64_t p = outer[i]; p < outer[i + 1]; ++p) block.columns.push_back(static_cast<PetscInt>(full.innerIndexPtr()[p]));
    block.start.push_back(static_cast<PetscInt>(block.columns.size()));
  }
  return block;
}

// Rows of M̄ = M_s ⊗ I3 for nodes [first, end), from the full scalar M_s.
RowBlock vector_mass_block_of(const FullRows& scalar, Eigen::Index first, Eigen::Index end) {
  RowBlock block;
  for (Eigen::Index i = first; i < end; ++i)
    for (int c = 0; c < 3; ++c) {
      for (FullRows::InnerIterator it(scalar, i); it; ++it) {
        block.columns.push_back(static_cast<PetscInt>(3 * it.index() + c));
        block.values.push_back(it.value());
      }
      block.start.push_back(static_cast<PetscInt>(block.columns.size()));
    }
  return block;
}

int count_of(std::size_t size) {
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::runtime_error("distributed matrix: one rank's block exceeds 2^31 entries; use more MPI ranks");
  return static_cast<int>(size);
}

void send_block(const RowBlock& block, int destination) {
  std::int64_t entries = static_cast<std::int64_t>(block.columns.size());
  MPI_Send(&entries, 1, MPI_INT64_T, destination, 0, PETSC_COMM_WORLD);
  MPI_Send(block.start.data(), count_of(block.start.size()), MPIU_INT, destination, 1, PETSC_COMM_WORLD);
  MPI_Send(block.columns.data(), count_of(block.columns.size()), MPIU_INT, destination, 2, PETSC_COMM_WORLD);
  MPI_Send(block.values.data(), count_of(block.values.size()), MPIU_SCALAR, destination, 3, PETSC_COMM_WORLD);
}

RowBlock receive_block(PetscInt rows) {
  std::int64_t entries = 0;
  MPI_Recv(&entries, 1, MPI_INT64_T, 0, 0, PETSC_COMM_WORLD, MPI_STATUS_IGNORE);
  RowBlock block;
  block.start.resize(static_cast<std::size_t>(rows) + 1);
  block.columns.resize(static_cast<std::size_t>(entries));
  block.values.resize(static_cast<std::size_t>(entries));
  MPI_Recv(block.start.data(), count_of(block.start.size()), MPIU_INT, 0, 1, PETSC_COMM_WORLD, MPI_STATUS_IGNORE);
  MPI_Recv(block.columns.data(), count_of(block.columns.size()), MPIU_INT, 0, 2, PETSC_COMM_WORLD, MPI_STATUS_IGNORE);
  MPI_Recv(block.values.data(), count_of(block.values.size()), MPIU_SCALAR, 0, 3, PETSC_COMM_WORLD, MPI_STATUS_IGNORE);
  return block;
}

Mat create_matrix(RowBlock& block, PetscInt local_rows, PetscInt global_rows, const char* name) {
  Mat matrix = nullptr;
  check(MatCreateMPIAIJWithArrays(PETSC_COMM_WORLD, local_rows, local_rows, global_rows, global_rows, block.start.data(),
                                  block.columns.data(), block.values.data(), &matrix),
        name);
  check(MatSetOption(matrix, MAT_SYMMETRIC, PETSC_TRUE), name);
  check(MatSetOption(matrix, MAT_SYMMETRY_ETERNAL, PETSC_TRUE), name);
  return matrix;
}

KSP factor_solver(EPS eps) {
  ST st = nullptr;
  KSP ksp = nullptr;
  check(EPSGetST(eps, &st), "EPSGetST");
  check(STGetKSP(st, &ksp), "STGetKSP");
  return ksp;
}

}  // namespace

DistributedShiftInvert::DistributedShiftInvert(const SparseMatrix* stiffness_upper, const SparseMatrix* scalar_mass_upper,
                                               const Eigen::MatrixXd* deflation) {
  const int me = rank(), ranks = size();
  std::int64_t header[2] = {0, 0};
  if (me == 0) {
    header[0] = scalar_mass_upper->rows();
    header[1] = deflation->cols();
  }
  MPI_Bcast(header, 2, MPI_INT64_T, 0, PETSC_COMM_WORLD);
  if (3 * header[0] > std::numeric_limits<PetscInt>::max())
    throw std::runtime_error(fmt::format("distributed matrix: {} DOFs exceed this PETSc's 32-bit indices", 3 * header[0]));
  const auto n_nodes = static_cast<PetscInt>(header[0]);
  rows_ = 3 * n_nodes;
  const PetscInt local_rows = 3 * (first_node(n_nodes, me + 1, ranks) - first_node(n_nodes, me, ranks));
  RowBlock k_block, m_block;
  if (me == 0) {
    // Both triangles, by rows; each rank gets its rows, rank 0 keeps its own last.
    FullRows full_k = stiffness_upper->selfadjointView<Eigen::Upper>();
    FullRows full_m = scalar_mass_upper->selfadjointView<Eigen::Upper>();
    for (int q = ranks - 1; q >= 0; --q) {
      const PetscInt a = first_node(n_nodes, q, ranks), b = first_node(n_nodes, q + 1, ranks);
      RowBlock kb = block_of(full_k, 3 * a, 3 * b), mb = vector_mass_block_of(full_m, a, b);
      if (q == 0) {
        k_block = std::move(kb);
        m_block = std::move(mb);
      } else {
        send_block(kb, q);
        send_block(mb, q);
      }
    }
  } else {
    k_block = receive_block(local_rows);
    m_block = receive_block(local_rows);
  }
  stiffness_ = create_matrix(k_block, local_rows, rows_, "distributed K");
  mass_ = create_matrix(m_block, local_rows, rows_, "distributed M");
  check(MatCreateVecs(stiffness_, &work_, &work_out_), "MatCreateVecs");
  check(VecScatterCreateToZero(work_, &to_zero_, &gathered_), "VecScatterCreateToZero");
  deflation_.resize(static_cast<std::size_t>(header[1]), nullptr);
  for (std::size_t k = 0; k < deflation_.size(); ++k) {
    check(VecDuplicate(work_, &deflation_[k]), "VecDuplicate");
    to_distributed(me == 0 ? deflation->col(static_cast<Eigen::Index>(k)).data() : nullptr, deflation_[k]);
  }
}

DistributedShiftInvert::~DistributedShiftInvert() {
  EPSDestroy(&eps_);
  for (Vec& v : deflation_) VecDestroy(&v);
  VecScatterDestroy(&to_zero_);
  VecDestroy(&gathered_);
  VecDestroy(&work_);
  VecDestroy(&work_out_);
  MatDestroy(&stiffness_);
  MatDestroy(&mass_);
}

void DistributedShiftInvert::to_distributed(const double* x, Vec v) {
  if (rank() == 0) {
    PetscScalar* whole = nullptr;
    check(VecGetArray(gathered_, &whole), "VecGetArray");
    std::memcpy(whole, x, static_cast<std::size_t>(rows_) * sizeof(double));
    check(VecRestoreArray(gathered_, &whole), "VecRestoreArray");
  }
  check(VecScatterBegin(to_zero_, gathered_, v, INSERT_VALUES, SCATTER_REVERSE), "VecScatterBegin");
  check(VecScatterEnd(to_zero_, gathered_, v, INSERT_VALUES, SCATTER_REVERSE), "VecScatterEnd");
}

void DistributedShiftInvert::to_root(Vec v, double* x) {
  check(VecScatterBegin(to_zero_, v, gathered_, INSERT_VALUES, SCATTER_FORWARD), "VecScatterBegin");
  check(VecScatterEnd(to_zero_, v, gathered_, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
  if (rank() == 0) {
    const PetscScalar* whole = nullptr;
    check(VecGetArrayRead(gathered_, &whole), "VecGetArrayRead");
    std::memcpy(x, whole, static_cast<std::size_t>(rows_) * sizeof(double));
    check(VecRestoreArrayRead(gathered_, &whole), "VecRestoreArrayRead");
  }
}

void DistributedShiftInvert::set_shift(double sigma) {
  MPI_Bcast(&sigma, 1, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
  sigma_ = sigma;
  check(EPSDestroy(&eps_), "EPSDestroy");
  check(EPSCreate(PETSC_COMM_WORLD, &eps_), "EPSCreate");
  check(EPSSetOperators(eps_, stiffness_, mass_), "EPSSetOperators");
  check(EPSSetProblemType(eps_, EPS_GHEP), "EPSSetProblemType");
  check(EPSSetType(eps_, EPSKRYLOVSCHUR), "EPSSetType");
  // Nearest to sigma in magnitude: for sigma below the spectrum, the lowest eigenvalues in ascending order.
  check(EPSSetWhichEigenpairs(eps_, EPS_TARGET_MAGNITUDE), "EPSSetWhichEigenpairs");
  check(EPSSetTarget(eps_, sigma), "EPSSetTarget");
  ST st = nullptr;
  check(EPSGetST(eps_, &st), "EPSGetST");
  check(STSetType(st, STSINVERT), "STSetType");
  // M̄'s pattern lies inside K̄'s (both couple the nodes of an element): K̄ - sigma M̄ keeps K̄'s pattern.
  check(STSetMatStructure(st, SUBSET_NONZERO_PATTERN), "STSetMatStructure");
  KSP ksp = factor_solver(eps_);
  check(KSPSetType(ksp, KSPPREONLY), "KSPSetType");
  PC pc = nullptr;
  check(KSPGetPC(ksp, &pc), "KSPGetPC");
  check(PCSetType(pc, PCCHOLESKY), "PCSetType");
  check(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "PCFactorSetMatSolverType");
  // PETSC_OPTIONS may tune the solver, e.g. -mat_mumps_icntl_22 1 for MUMPS's out-of-core factor.
  check(EPSSetFromOptions(eps_), "EPSSetFromOptions");
  const auto start = std::chrono::steady_clock::now();
  check(EPSSetUp(eps_), "SLEPc: factorization of K - sigma M by MUMPS");
  factorize_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  read_factor_statistics();
}

void DistributedShiftInvert::read_factor_statistics() {
  PC pc = nullptr;
  Mat factor = nullptr;
  check(KSPGetPC(factor_solver(eps_), &pc), "KSPGetPC");
  check(PCFactorGetMatrix(pc, &factor), "PCFactorGetMatrix");
  PetscInt negative_pivots = 0, entries = 0, megabytes = 0;
  PetscReal flops = 0.0;
  check(MatMumpsGetInfog(factor, 12, &negative_pivots), "MatMumpsGetInfog(12)");
  check(MatMumpsGetInfog(factor, 29, &entries), "MatMumpsGetInfog(29)");
  check(MatMumpsGetInfog(factor, 22, &megabytes), "MatMumpsGetInfog(22)");
  check(MatMumpsGetRinfog(factor, 3, &flops), "MatMumpsGetRinfog(3)");
  // INFOG(29) counts entries; a negative value counts millions of them.
  factor_entries_ = entries >= 0 ? static_cast<double>(entries) : -1e6 * static_cast<double>(entries);
  factor_flops_ = flops;
  factor_megabytes_ = static_cast<double>(megabytes);
  if (negative_pivots > 0)
    throw std::runtime_error(fmt::format("MUMPS: K - sigma M is not positive definite at sigma = {:.6g} "
                                         "({} negative pivots)", sigma_, negative_pivots));
}

DistributedEigenPairs DistributedShiftInvert::eigenpairs(int nev, int ncv, double tolerance, int max_restarts,
                                                         const Eigen::VectorXd* start) {
  int sizes[3] = {nev, ncv, max_restarts};
  MPI_Bcast(sizes, 3, MPI_INT, 0, PETSC_COMM_WORLD);
  MPI_Bcast(&tolerance, 1, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
  nev = sizes[0];
  check(EPSSetDimensions(eps_, nev, sizes[1], PETSC_DEFAULT), "EPSSetDimensions");
  check(EPSSetTolerances(eps_, tolerance, sizes[2]), "EPSSetTolerances");
  // Neither space persists from one EPSSolve to the next.
  if (!deflation_.empty())
    check(EPSSetDeflationSpace(eps_, static_cast<PetscInt>(deflation_.size()), deflation_.data()), "EPSSetDeflationSpace");
  to_distributed(rank() == 0 ? start->data() : nullptr, work_);
  check(EPSSetInitialSpace(eps_, 1, &work_), "EPSSetInitialSpace");
  KSP ksp = factor_solver(eps_);
  PetscInt solves_before = 0, solves_after = 0;
  check(KSPGetTotalIterations(ksp, &solves_before), "KSPGetTotalIterations");
  check(EPSSolve(eps_), "SLEPc EPSSolve");
  PetscInt converged = 0, iterations = 0;
  check(EPSGetConverged(eps_, &converged), "EPSGetConverged");
  check(EPSGetIterationNumber(eps_, &iterations), "EPSGetIterationNumber");
  if (converged < nev)
    throw std::runtime_error(fmt::format("SLEPc: no convergence after {} restarts ({} of {} eigenpairs converged)",
                                         iterations, converged, nev));
  DistributedEigenPairs result;
  result.iterations = static_cast<int>(iterations);
  if (rank() == 0) {
    result.eigenvalues.resize(nev);
    result.vectors.resize(rows_, nev);
  }
  std::vector<double> values(static_cast<std::size_t>(nev));
  for (int k = 0; k < nev; ++k) {
    check(EPSGetEigenpair(eps_, k, &values[static_cast<std::size_t>(k)], nullptr, work_out_, nullptr), "EPSGetEigenpair");
    to_root(work_out_, rank() == 0 ? result.vectors.col(k).data() : nullptr);
  }
  // The vectors are purified (one more solve each) when they are first asked for.
  check(KSPGetTotalIterations(factor_solver(eps_), &solves_after), "KSPGetTotalIterations");
  result.operator_applies = static_cast<int>(solves_after - solves_before);
  if (rank() == 0) {  // ascending (EPS orders by distance to the target, the same for sigma below the spectrum)
    std::vector<int> order(static_cast<std::size_t>(nev));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return values[a] < values[b]; });
    Eigen::MatrixXd sorted(rows_, nev);
    for (int k = 0; k < nev; ++k) {
      result.eigenvalues(k) = values[order[k]];
      sorted.col(k) = result.vectors.col(order[k]);
    }
    result.vectors = std::move(sorted);
  }
  return result;
}

void DistributedShiftInvert::solve(const double* x, double* y) {
  to_distributed(x, work_);
  check(KSPSolve(factor_solver(eps_), work_, work_out_), "MUMPS solve");
  to_root(work_out_, y);
}

}  // namespace flexbody::preprocess::parallel
