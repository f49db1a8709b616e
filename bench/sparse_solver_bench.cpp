// sparse_solver_bench: which sparse direct solver factorizes the constant core's reduced Newton matrix (issue 27:
// "measure the candidates and say why the one you chose wins"). The matrices are the runtime's own: chains of N
// copies of a body file, body k's interface A pinned to body k-1's interface B by a revolute joint about z, body
// 0 to ground, assembled exactly; ConstantCoreNewton builds the reduced matrix [S_r J_rᵀ; J_r 0] (after each GCMS
// body's ξ elimination) for h = 1 ms, ρ∞ = 0.9, at a generic state (below); the solvers get its nonzeros, the pattern
// SparseReducedSolver factorizes. On each:
//
// - KLU (SuiteSparse) as the runtime sets it up: klu_analyze (COLAMD, no BTF) once, klu_factor (pivoting),
//   klu_refactor (the pivot sequence kept: what the integrator does for a matrix of the same pattern), klu_solve;
//   also with KLU's default ordering (BTF + AMD), with AMD alone, and on the blocks' dense pattern (zeros
//   included: what the runtime factorized before 0.12, with BTF + AMD then);
// - Eigen's SparseLU (COLAMD): analyzePattern once, factorize, solve;
// - Eigen's SimplicialLDLT (AMD) on the quasi-definite form: the constraint block −δ I instead of 0 with δ = 1e-10 of
//   the largest entry, so that an LDLᵀ without pivoting exists in any order (Vanderbei 1995); its solution is off by
//   O(δ), so the residual of the unregularized system is reported with it.
//
// Each time is the best of 5 repetitions. Prints a table and writes a CSV (bench/sparse_solver_plot.py draws it).
//
//   sparse_solver_bench BODY.fbh5 INTERFACE_A INTERFACE_B OUTPUT.csv [N ...]
//   e.g. sparse_solver_bench bench/results/work/scale/bracket.fbh5 bore_1 bore_2 bench/results/sparse_solver_bench.csv
#include "integrator/newton_solvers.hpp"

#include "flexbody/format/body_file.hpp"
#include "flexbody/runtime/body_model.hpp"
#include "flexbody/runtime/marker.hpp"
#include "flexbody/runtime/system.hpp"

#include <Eigen/Geometry>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <fmt/format.h>
#include <klu.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace fr = flexbody::runtime;

namespace {

constexpr int kRepeats = 5;

// The best of kRepeats runs of f, in µs.
double best_us(const std::function<void()>& f) {
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < kRepeats; ++k) {
    const auto start = std::chrono::steady_clock::now();
    f();
    best = std::min(best, std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

struct Chain {
  fr::System system;
  Eigen::SparseMatrix<double> reduced;
  Eigen::Index constraint_rows = 0;
};

// N copies of `model` in a line from interface a to interface b, joined by revolute joints about z.
Chain chain(const fr::BodyModel& model, int n, const std::string& a, const std::string& b) {
  Chain c;
  const fr::Marker a0 = fr::interface_marker(model, 0, "probe", a), b0 = fr::interface_marker(model, 0, "probe", b);
  const Eigen::VectorXd at_rest = [&] {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(model.coordinate_count());
    q.segment<3>(3) = Eigen::Vector3d::UnitX(), q.segment<3>(6) = Eigen::Vector3d::UnitY(), q.segment<3>(9) = Eigen::Vector3d::UnitZ();
    return q;
  }();
  const Eigen::Vector3d pitch = fr::marker_position(b0, at_rest) - fr::marker_position(a0, at_rest);
  for (int k = 0; k < n; ++k) {
    fr::BodyState state;
    state.position = k * pitch;
    std::string name = "b";
    name += std::to_string(k);
    c.system.add_body(name, model, state);
  }
  const Eigen::VectorXd q0 = c.system.initial_coordinates();
  for (int k = 0; k < n; ++k) {
    std::string name = "j";
    name += std::to_string(k);
    const fr::Marker here = fr::interface_marker(c.system.model(k), k, c.system.body_name(k), a);
    const Eigen::VectorXd q_k = c.system.body_coordinates(q0, k);
    if (k == 0) {
      c.system.add_joint(fr::make_joint(name, fr::JointType::revolute, here, fr::ground_marker(fr::marker_position(here, q_k)),
                                        Eigen::Vector3d::UnitZ(), q_k, Eigen::VectorXd()));
    } else {
      const fr::Marker there = fr::interface_marker(c.system.model(k - 1), k - 1, c.system.body_name(k - 1), b);
      c.system.add_joint(fr::make_joint(name, fr::JointType::revolute, here, there, Eigen::Vector3d::UnitZ(), q_k,
                                        c.system.body_coordinates(q0, k - 1)));
    }
  }
  // β' and γ' of generalized-α at h = 1 ms, ρ∞ = 0.9 (generalized_alpha.hpp).
  const double rho = 0.9, h = 1e-3;
  const double alpha_m = (2 * rho - 1) / (rho + 1), alpha_f = rho / (rho + 1), gamma = 0.5 + alpha_f - alpha_m;
  const double beta = 0.25 * (gamma + 0.5) * (gamma + 0.5);
  fr::detail::CoreInverses cores;
  fr::detail::ConstantCoreNewton newton(c.system, (1 - alpha_m) / (beta * h * h * (1 - alpha_f)), gamma / (beta * h), true, cores);
  // A generic state, so that no entry is zero by accident: every body turned by 0.01 rad about (1, 2, 3) (the chain
  // starts along the axes, where A = I zeroes many products) and random multipliers (the reference rows' curvature).
  Eigen::VectorXd q = q0;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.01, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  for (int k = 0; k < n; ++k) Eigen::Map<Eigen::Matrix3d>(q.data() + c.system.offset(k) + 3) = turn;
  Eigen::SparseMatrix<double> jacobian;
  c.system.sparse_constraint_jacobian(0.0, q, jacobian);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> uniform(-1e-6, 1e-6);
  Eigen::VectorXd mu(jacobian.rows());
  for (Eigen::Index k = 0; k < mu.size(); ++k) mu(k) = uniform(random);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(q.size());
  newton.factor(0.0, q, zero, zero, mu, jacobian);
  c.reduced = newton.reduced().matrix();  // every entry of the blocks, zeros included
  c.constraint_rows = jacobian.rows();
  return c;
}

struct Timing {
  double analyse = 0, factor = 0, refactor = 0, solve = 0, residual = 0;
  long factor_nonzeros = 0;
};

double relative_residual(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  return (a * x - b).norm() / b.norm();
}

// KLU with the runtime's settings (COLAMD, no BTF: reduced_solver.cpp) by default.
Timing time_klu(Eigen::SparseMatrix<double> a, const Eigen::VectorXd& b, bool btf = false, int ordering = 1) {
  a.makeCompressed();
  const int n = static_cast<int>(a.rows());
  klu_common common;
  klu_defaults(&common);
  common.btf = btf ? 1 : 0;
  common.ordering = ordering;  // 0 AMD, 1 COLAMD
  Timing t;
  klu_symbolic* symbolic = nullptr;
  t.analyse = best_us([&] {
    if (symbolic) klu_free_symbolic(&symbolic, &common);
    symbolic = klu_analyze(n, a.outerIndexPtr(), a.innerIndexPtr(), &common);
  });
  if (!symbolic) throw std::runtime_error("klu_analyze failed");
  klu_numeric* numeric = nullptr;
  t.factor = best_us([&] {
    if (numeric) klu_free_numeric(&numeric, &common);
    numeric = klu_factor(a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr(), symbolic, &common);
  });
  if (!numeric) throw std::runtime_error("klu_factor failed");
  t.refactor = best_us([&] { klu_refactor(a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr(), symbolic, numeric, &common); });
  Eigen::VectorXd x;
  t.solve = best_us([&] {
    x = b;
    klu_solve(symbolic, numeric, n, 1, x.data(), &common);
  });
  t.residual = relative_residual(a, x, b);
  t.factor_nonzeros = static_cast<long>(numeric->lnz + numeric->unz);
  klu_free_numeric(&numeric, &common);
  klu_free_symbolic(&symbolic, &common);
  return t;
}

Timing time_sparse_lu(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& b) {
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu;
  Timing t;
  t.analyse = best_us([&] { lu.analyzePattern(a); });
  t.factor = best_us([&] { lu.factorize(a); });
  if (lu.info() != Eigen::Success) throw std::runtime_error("SparseLU failed: " + lu.lastErrorMessage());
  t.refactor = t.factor;  // SparseLU has no refactorization that keeps the pivots
  Eigen::VectorXd x;
  t.solve = best_us([&] { x = lu.solve(b); });
  t.residual = relative_residual(a, x, b);
  t.factor_nonzeros = static_cast<long>(lu.nnzL() + lu.nnzU());
  return t;
}

Timing time_quasi_definite_ldlt(const Eigen::SparseMatrix<double>& a, Eigen::Index constraint_rows, const Eigen::VectorXd& b) {
  Eigen::SparseMatrix<double> regularized = a;
  const double delta = 1e-10 * a.coeffs().cwiseAbs().maxCoeff();
  for (Eigen::Index k = a.rows() - constraint_rows; k < a.rows(); ++k) regularized.coeffRef(k, k) -= delta;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt;
  Timing t;
  t.analyse = best_us([&] { ldlt.analyzePattern(regularized); });
  t.factor = best_us([&] { ldlt.factorize(regularized); });
  if (ldlt.info() != Eigen::Success) throw std::runtime_error("SimplicialLDLT failed");
  t.refactor = t.factor;
  Eigen::VectorXd x;
  t.solve = best_us([&] { x = ldlt.solve(b); });
  t.residual = relative_residual(a, x, b);
  t.factor_nonzeros = static_cast<long>(ldlt.matrixL().nestedExpression().nonZeros());
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: sparse_solver_bench BODY.fbh5 INTERFACE_A INTERFACE_B OUTPUT.csv [N ...]\n");
    return 2;
  }
  try {
    const flexbody::format::BodyData body = flexbody::format::read_body_file(argv[1]);
    std::vector<int> sizes;
    for (int k = 5; k < argc; ++k) sizes.push_back(std::stoi(argv[k]));
    if (sizes.empty()) sizes = {4, 16, 64, 256, 1024};
    std::ofstream csv(argv[4]);
    if (!csv) throw std::runtime_error(std::string("cannot write ") + argv[4]);
    csv << "kind,bodies,size,nonzeros,solver,analyse_us,factor_us,refactor_us,solve_us,relative_residual,factor_nonzeros\n";
    fmt::print("{:>6} {:>5} {:>6} {:>8} | {:>9} {:>9} {:>9} {:>8} {:>8} {:>9} | solver\n", "kind", "N", "size", "nnz(A)",
               "analyse", "factor", "refactor", "solve", "residual", "nnz(LU)");
    for (const char* kind : {"rigid", "gcms"}) {
      const fr::BodyModel model = fr::make_body_model(body, std::string(kind) == "rigid" ? 0 : 6, argv[1]);
      for (const int n : sizes) {
        const Chain c = chain(model, n, argv[2], argv[3]);
        std::mt19937 random(7);
        std::normal_distribution<double> normal;
        Eigen::VectorXd rhs(c.reduced.rows());
        for (Eigen::Index k = 0; k < rhs.size(); ++k) rhs(k) = normal(random);
        Eigen::SparseMatrix<double> nonzeros = c.reduced;  // the pattern the runtime factorizes
        nonzeros.prune(0.0);
        const std::pair<const char*, Timing> rows[] = {
            {"klu", time_klu(nonzeros, rhs)},
            {"klu_amd_btf", time_klu(nonzeros, rhs, true, 0)},
            {"klu_amd", time_klu(nonzeros, rhs, false, 0)},
            {"sparselu", time_sparse_lu(nonzeros, rhs)},
            {"ldlt_quasidefinite", time_quasi_definite_ldlt(nonzeros, c.constraint_rows, rhs)},
            {"klu_block_pattern_amd_btf", time_klu(c.reduced, rhs, true, 0)}};
        for (const auto& [solver, t] : rows) {
          fmt::print("{:>6} {:>5} {:>6} {:>8} | {:>7.1f}us {:>7.1f}us {:>7.1f}us {:>6.1f}us {:>8.1e} {:>9} | {}\n", kind, n,
                     c.reduced.rows(), c.reduced.nonZeros(), t.analyse, t.factor, t.refactor, t.solve, t.residual,
                     t.factor_nonzeros, solver);
          csv << fmt::format("{},{},{},{},{},{:.3f},{:.3f},{:.3f},{:.3f},{:.3e},{}\n", kind, n, c.reduced.rows(),
                             c.reduced.nonZeros(), solver, t.analyse, t.factor, t.refactor, t.solve, t.residual,
                             t.factor_nonzeros);
        }
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sparse_solver_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
