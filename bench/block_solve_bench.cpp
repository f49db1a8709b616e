// block_solve_bench: the cost of CHOLMOD's solves with b right-hand sides per pass over the factor, against b, on a
// real mesh: what the block-lanczos backend trades its larger Krylov basis against (bench/README.md, "Block Lanczos").
//
//   block_solve_bench MESH UNIT OUTPUT.csv [B ...]      e.g. block_solve_bench bracket.msh mm out.csv 1 2 4 8 16 32
//
// Assembles K̄ and M_s of the steel part, factorizes K̄ - sigma M̄ at fbprep's automatic shift (rigid-body modes
// deflated, as in fbprep), then times one pass with b random right-hand sides, the better of two, for each b.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/rigid_body_modes.hpp"
#include "flexbody/preprocess/shift_invert_operator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fp = flexbody::preprocess;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 4) {
    std::fprintf(stderr, "usage: block_solve_bench MESH UNIT OUTPUT.csv [B ...]\n");
    return 2;
  }
  fp::GmshImportOptions import_options;
  import_options.order = 1;  // the linear mesh it assembles (and its recorded results)
  import_options.unit = fp::length_unit_from_string(argv[2]);
  if (!import_options.unit) throw std::invalid_argument(fmt::format("unit '{}' is not one of mm, cm, m, in", argv[2]));
  std::vector<Eigen::Index> blocks;
  for (int i = 4; i < argc; ++i) blocks.push_back(std::stol(argv[i]));
  if (blocks.empty()) blocks = {1, 2, 4, 8, 12, 16, 24, 32};

  const fp::TetMesh mesh = fp::import_tet_mesh(argv[1], import_options).mesh;
  const fp::Material steel{"steel", 210e9, 0.3, 7850.0};
  const fp::NodeGraph graph = fp::NodeGraph::build(mesh);
  const auto geometry = fp::element_geometries(mesh);
  const fp::SparseMatrix k = fp::assemble_stiffness(mesh, graph, geometry, steel);
  const fp::SparseMatrix m = fp::assemble_scalar_mass(mesh, graph, geometry, steel.density, fp::MassScheme::consistent);
  fp::CholmodShiftSolve op(k, m, fp::rigid_body_modes(mesh.nodes, m));
  auto start = std::chrono::steady_clock::now();
  op.set_shift(fp::automatic_shift(mesh.nodes, steel));
  const double factorize_s = seconds_since(start);
  const Eigen::Index n = op.rows();
  fmt::print("{} DOFs, nnz(L) = {:.3g}, analysis {:.2f} s, factorization {:.2f} s\n", n, op.stats().factor_nonzeros,
             op.stats().analyze_seconds, factorize_s);

  std::ofstream csv(argv[3]);
  csv << "dofs,factor_nonzeros,block,pass_s,per_vector_s,relative_per_vector\n";
  fmt::print("{:>5} {:>10} {:>14} {:>22}\n", "b", "pass [s]", "per vector [s]", "per vector / b = 1's");
  double single = 0.0;
  for (const Eigen::Index b : blocks) {
    const Eigen::MatrixXd x = Eigen::MatrixXd::Random(n, b);
    Eigen::MatrixXd y(n, b);
    double best = 1e300;
    for (int repeat = 0; repeat < 2; ++repeat) {
      start = std::chrono::steady_clock::now();
      op.perform_block(x.data(), y.data(), b);
      best = std::min(best, seconds_since(start));
    }
    if (b == 1 || single == 0.0) single = best / static_cast<double>(b);
    const double per_vector = best / static_cast<double>(b);
    fmt::print("{:>5} {:>10.3f} {:>14.3f} {:>22.3f}\n", b, best, per_vector, per_vector / single);
    csv << fmt::format("{},{},{},{},{},{}\n", n, op.stats().factor_nonzeros, b, best, per_vector, per_vector / single);
    std::fflush(stdout);
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "block_solve_bench: %s\n", e.what());
  return 1;
}
