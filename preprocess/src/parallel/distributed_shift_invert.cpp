#include "distributed_shift_invert.hpp"

#include "petsc_runtime.hpp"

#include <petscmat.h>

#include <fmt/format.h>

#include <sys/resource.h>

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

// The first node of rank q: whole nodes (three rows each), as evenly as possible.
PetscInt first_node(PetscInt n_nodes, int q, int ranks) {
  return n_nodes / ranks * q + std::min<PetscInt>(q, n_nodes % ranks);
}

// One rank's rows in PETSc's CSR form: local row starts, global column indices (sorted in each row).
struct RowBlock {
  std::vector<PetscInt> start{0};
  std::vector<PetscInt> columns;
  std::vector<PetscScalar> values;
};

// Every rank's rows of the full symmetric matrix whose upper triangle is `upper` (column j holds rows i <= j),
// without forming the full matrix: (i, j) goes to row i and, for i != j, (j, i) to row j. Columns are visited in
// ascending order, so each row's columns come out sorted. `first_row` has ranks + 1 entries.
std::vector<RowBlock> row_blocks(const SparseMatrix& upper, const std::vector<PetscInt>& first_row) {
  const auto ranks = static_cast<int>(first_row.size()) - 1;
  const Eigen::Index n = upper.rows();
  std::vector<int> owner(static_cast<std::size_t>(n));
  for (int q = 0; q < ranks; ++q)
    std::fill(owner.begin() + first_row[q], owner.begin() + first_row[q + 1], q);
  std::vector<std::int64_t> length(static_cast<std::size_t>(n), 0);
  for (Eigen::Index j = 0; j < upper.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(upper, j); it; ++it) {
      ++length[static_cast<std::size_t>(it.row())];
      if (it.row() != j) ++length[static_cast<std::size_t>(j)];
    }
  std::vector<RowBlock> blocks(static_cast<std::size_t>(ranks));
  std::vector<std::int64_t> cursor(static_cast<std::size_t>(n));
  for (int q = 0; q < ranks; ++q) {
    RowBlock& block = blocks[static_cast<std::size_t>(q)];
    std::int64_t entries = 0;
    for (PetscInt r = first_row[q]; r < first_row[q + 1]; ++r) {
      cursor[static_cast<std::size_t>(r)] = entries;
      entries += length[static_cast<std::size_t>(r)];
      if (entries > std::numeric_limits<PetscInt>::max())
        throw std::runtime_error("distributed matrix: one rank's block exceeds 2^31 entries; use more MPI ranks");
      block.start.push_back(static_cast<PetscInt>(entries));
    }
    block.columns.resize(static_cast<std::size_t>(entries));
    block.values.resize(static_cast<std::size_t>(entries));
  }
  auto put = [&](Eigen::Index row, Eigen::Index column, double value) {
    RowBlock& block = blocks[static_cast<std::size_t>(owner[static_cast<std::size_t>(row)])];
    const auto p = static_cast<std::size_t>(cursor[static_cast<std::size_t>(row)]++);
    block.columns[p] = static_cast<PetscInt>(column);
    block.values[p] = value;
  };
  for (Eigen::Index j = 0; j < upper.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(upper, j); it; ++it) {
      put(it.row(), j, it.value());
      if (it.row() != j) put(j, it.row(), it.value());
    }
  return blocks;
}

// M̄ = M_s ⊗ I3's rows for the nodes of each rank, from the full scalar rows of M_s (one block over all nodes).
std::vector<RowBlock> vector_mass_blocks(const RowBlock& scalar, const std::vector<PetscInt>& first_node_of) {
  std::vector<RowBlock> blocks(first_node_of.size() - 1);
  for (std::size_t q = 0; q + 1 < first_node_of.size(); ++q) {
    RowBlock& block = blocks[q];
    for (PetscInt i = first_node_of[q]; i < first_node_of[q + 1]; ++i)
      for (int c = 0; c < 3; ++c) {
        for (PetscInt p = scalar.start[static_cast<std::size_t>(i)]; p < scalar.start[static_cast<std::size_t>(i) + 1]; ++p) {
          block.columns.push_back(3 * scalar.columns[static_cast<std::size_t>(p)] + c);
          block.values.push_back(scalar.values[static_cast<std::size_t>(p)]);
        }
        block.start.push_back(static_cast<PetscInt>(block.columns.size()));
      }
  }
  return blocks;
}

void send_block(const RowBlock& block, int destination) {
  MPI_Send(block.start.data(), static_cast<int>(block.start.size()), MPIU_INT, destination, 1, PETSC_COMM_WORLD);
  MPI_Send(block.columns.data(), static_cast<int>(block.columns.size()), MPIU_INT, destination, 2, PETSC_COMM_WORLD);
  MPI_Send(block.values.data(), static_cast<int>(block.values.size()), MPIU_SCALAR, destination, 3, PETSC_COMM_WORLD);
}

void receive_block(RowBlock& block) {  // sized by the caller
  MPI_Recv(block.start.data(), static_cast<int>(block.start.size()), MPIU_INT, 0, 1, PETSC_COMM_WORLD, MPI_STATUS_IGNORE);
  MPI_Recv(block.columns.data(), static_cast<int>(block.columns.size()), MPIU_INT, 0, 2, PETSC_COMM_WORLD,
           MPI_STATUS_IGNORE);
  MPI_Recv(block.values.data(), static_cast<int>(block.values.size()), MPIU_SCALAR, 0, 3, PETSC_COMM_WORLD,
           MPI_STATUS_IGNORE);
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

// Every step that allocates or may fail on one rank alone is agreed on before the next communication, so a
// failure on one rank (bad_alloc on rank 0 for the blocks, on a worker for its share) throws on every rank
// instead of leaving the others waiting in a send or a receive.
DistributedShiftInvert::DistributedShiftInvert(const SparseMatrix* stiffness_upper, const SparseMatrix* scalar_mass_upper,
                                               const Eigen::MatrixXd* deflation) {
  const int me = rank(), ranks = size();
  std::int64_t header[2] = {0, 0};
  if (me == 0) {
    header[0] = scalar_mass_upper->rows();
    header[1] = deflation->cols();
  }
  MPI_Bcast(header, 2, MPI_INT64_T, 0, PETSC_COMM_WORLD);
  if (3 * header[0] > std::numeric_limits<PetscInt>::max())  // the same on every rank
    throw std::runtime_error(fmt::format("distributed matrix: {} DOFs exceed this PETSc's 32-bit indices", 3 * header[0]));
  const auto n_nodes = static_cast<PetscInt>(header[0]);
  rows_ = 3 * n_nodes;
  std::vector<PetscInt> first_node_of(static_cast<std::size_t>(ranks) + 1), first_row(first_node_of.size());
  for (int q = 0; q <= ranks; ++q) {
    first_node_of[static_cast<std::size_t>(q)] = first_node(n_nodes, q, ranks);
    first_row[static_cast<std::size_t>(q)] = 3 * first_node_of[static_cast<std::size_t>(q)];
  }
  const PetscInt local_rows = first_row[static_cast<std::size_t>(me) + 1] - first_row[static_cast<std::size_t>(me)];

  std::vector<RowBlock> k_blocks, m_blocks;
  collective([&] {  // rank 0 builds every rank's rows
    if (me != 0) return;
    k_blocks = row_blocks(*stiffness_upper, first_row);
    const std::vector<PetscInt> all_nodes = {0, n_nodes};
    m_blocks = vector_mass_blocks(row_blocks(*scalar_mass_upper, all_nodes)[0], first_node_of);
  });
  std::vector<std::int64_t> entries(2 * static_cast<std::size_t>(ranks)), mine(2);
  if (me == 0)
    for (int q = 0; q < ranks; ++q) {
      entries[2 * static_cast<std::size_t>(q)] = static_cast<std::int64_t>(k_blocks[static_cast<std::size_t>(q)].columns.size());
      entries[2 * static_cast<std::size_t>(q) + 1] = static_cast<std::int64_t>(m_blocks[static_cast<std::size_t>(q)].columns.size());
    }
  MPI_Scatter(entries.data(), 2, MPI_INT64_T, mine.data(), 2, MPI_INT64_T, 0, PETSC_COMM_WORLD);
  RowBlock k_block, m_block;
  collective([&] {  // the workers make room for their rows
    if (me == 0) {
      k_block = std::move(k_blocks[0]);
      m_block = std::move(m_blocks[0]);
      return;
    }
    for (auto [block, count] : {std::pair{&k_block, mine[0]}, std::pair{&m_block, mine[1]}}) {
      block->start.resize(static_cast<std::size_t>(local_rows) + 1);
      block->columns.resize(static_cast<std::size_t>(count));
      block->values.resize(static_cast<std::size_t>(count));
    }
  });
  if (me == 0) {
    for (int q = 1; q < ranks; ++q) {
      send_block(k_blocks[static_cast<std::size_t>(q)], q);
      send_block(m_blocks[static_cast<std::size_t>(q)], q);
      k_blocks[static_cast<std::size_t>(q)] = RowBlock();
      m_blocks[static_cast<std::size_t>(q)] = RowBlock();
    }
  } else {
    receive_block(k_block);
    receive_block(m_block);
  }
  // If a creation fails on any rank, every rank releases what it made.
  try {
    collective([&] {
      stiffness_ = create_matrix(k_block, local_rows, rows_, "distributed K");
      k_block = RowBlock();  // PETSc copied it
      mass_ = create_matrix(m_block, local_rows, rows_, "distributed M");
      m_block = RowBlock();
      check(MatCreateVecs(stiffness_, &work_, &work_out_), "MatCreateVecs");
      check(VecScatterCreateToZero(work_, &to_zero_, &gathered_), "VecScatterCreateToZero");
      deflation_.resize(static_cast<std::size_t>(header[1]), nullptr);
      for (std::size_t k = 0; k < deflation_.size(); ++k) {
        check(VecDuplicate(work_, &deflation_[k]), "VecDuplicate");
        to_distributed(me == 0 ? deflation->col(static_cast<Eigen::Index>(k)).data() : nullptr, deflation_[k]);
      }
    });
  } catch (...) {
    release();
    throw;
  }
}

DistributedShiftInvert::~DistributedShiftInvert() { release(); }

void DistributedShiftInvert::release() {
  EPSDestroy(&eps_);
  for (Vec& v : deflation_) VecDestroy(&v);
  deflation_.clear();
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
  // Purification (one more solve per eigenvector) cleans vectors of a singular B's null space; M̄ is positive
  // definite, and ARPACK does without. Measured on the bracket at 41k DOFs, 26 modes: 73 solves instead of 99,
  // the same residuals.
  check(EPSSetPurify(eps_, PETSC_FALSE), "EPSSetPurify");
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
  // MUMPS counts the negative pivots of a root node factorized by ScaLAPACK (several ranks) only with ICNTL(13) = 1,
  // which keeps that node on one rank: without it an indefinite K - sigma M could pass the check below.
  if (size() > 1) {
    PetscBool given = PETSC_FALSE;
    check(PetscOptionsHasName(nullptr, nullptr, "-st_mat_mumps_icntl_13", &given), "PetscOptionsHasName");
    if (!given) check(PetscOptionsSetValue(nullptr, "-st_mat_mumps_icntl_13", "1"), "PetscOptionsSetValue");
  }
  // PETSC_OPTIONS may tune the solver (the factor's options carry the ST's prefix), e.g.
  // -st_mat_mumps_icntl_22 1 for MUMPS's out-of-core factor.
  check(EPSSetFromOptions(eps_), "EPSSetFromOptions");
  const auto start = std::chrono::steady_clock::now();
  check(EPSSetUp(eps_), "SLEPc: factorization of K - sigma M by MUMPS");
  factorize_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  measure_other_ranks_memory();
  read_factor_statistics();
}

void DistributedShiftInvert::measure_other_ranks_memory() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const double mine = rank() == 0 ? 0.0 : static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB on Linux
  double largest = 0.0;
  MPI_Reduce(&mine, &largest, 1, MPI_DOUBLE, MPI_MAX, 0, PETSC_COMM_WORLD);
  other_ranks_peak_megabytes_ = largest;
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
  DistributedEigenPairs result;
  collective([&] {  // rank 0 makes room for the vectors before the collective calls that fill them
    if (rank() != 0) return;
    result.eigenvalues.resize(nev);
    result.vectors.resize(rows_, nev);
  });
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
  result.iterations = static_cast<int>(iterations);
  std::vector<double> values(static_cast<std::size_t>(nev));
  for (int k = 0; k < nev; ++k) {
    check(EPSGetEigenpair(eps_, k, &values[static_cast<std::size_t>(k)], nullptr, work_out_, nullptr), "EPSGetEigenpair");
    to_root(work_out_, rank() == 0 ? result.vectors.col(k).data() : nullptr);
  }
  // Solves made while the vectors were asked for count too (none without purification, which set_shift turns off).
  check(KSPGetTotalIterations(factor_solver(eps_), &solves_after), "KSPGetTotalIterations");
  result.operator_applies = static_cast<int>(solves_after - solves_before);
  measure_other_ranks_memory();
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
