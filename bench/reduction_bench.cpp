// reduction_bench: speed against error of the runtime's reduced bodies, measured against the unreduced improved
// ACF (the sparse full-order reference) on the same mesh. Prints a table and writes CSV for
// bench/reduction_plot.py.
//
//   reduction_bench OUTPUT.csv
//
// The scene is the clamped-beam test's, on a finer mesh: a 0.5 x 0.05 x 0.05 m steel beam (40 x 4 x 4 cells of 6
// tetrahedra, 1025 nodes, 3075 DOFs) clamped at x = 0, gravity switched on at t = 0, 8 ms (1.3 periods of the first
// cantilever mode) with h = 2e-5 s and ρ∞ = 0.8. Reduced bodies: Craig-Bampton bases (the root an rbe2 interface)
// with 1 ... 32 fixed-interface modes, clamped by spherical joints at three root corners (every field is affine
// on the root patch, so this holds it all); the reference holds every root node. Error: the largest tip
// deflection difference over the run, relative to the largest deflection. Cost: µs per step, the fastest of
// three runs of the whole trajectory.
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/box_mesh.hpp"
#include "flexbody/preprocess/craig_bampton.hpp"
#include "flexbody/preprocess/free_free_modes.hpp"
#include "flexbody/preprocess/gcms_constants.hpp"
#include "flexbody/preprocess/interfaces.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "flexbody/runtime/full_order.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace fr = flexbody::runtime;
namespace fp = flexbody::preprocess;

namespace {

constexpr double kStep = 2e-5, kEnd = 8e-3;
constexpr int kRuns = 3;

struct Run {
  std::vector<double> tip_y;  ///< per step
  double microseconds_per_step = std::numeric_limits<double>::infinity();
  double iterations_per_step = 0.0;
};

// Integrates the system kRuns times from its initial state; keeps the fastest run's cost.
Run integrate(fr::System& system, int body, const fr::Marker& tip) {
  system.set_gravity(Eigen::Vector3d(0, -9.81, 0));
  fr::GeneralizedAlphaOptions options;
  options.rho_infinity = 0.8;
  options.step = kStep;
  Run run;
  for (int r = 0; r < kRuns; ++r) {
    fr::GeneralizedAlpha integrator(system, options);
    std::vector<double> y;
    const auto start = std::chrono::steady_clock::now();
    while (integrator.time() < kEnd - 0.5 * kStep) {
      integrator.step();
      y.push_back(fr::marker_position(tip, system.body_coordinates(integrator.coordinates(), body)).y());
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    run.microseconds_per_step = std::min(run.microseconds_per_step, 1e6 * seconds / static_cast<double>(y.size()));
    run.iterations_per_step = static_cast<double>(integrator.total_iterations()) / static_cast<double>(y.size());
    run.tip_y = std::move(y);
  }
  return run;
}

void hold(fr::System& system, const fr::Marker& m, const Eigen::VectorXd& q0, const std::string& name) {
  system.add_joint(fr::make_joint(name, fr::JointType::spherical, m, fr::ground_marker(fr::marker_position(m, q0)),
                                  Eigen::Vector3d::UnitZ(), q0, Eigen::VectorXd()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: reduction_bench OUTPUT.csv\n");
    return 2;
  }
  const fp::Material steel{"steel", 210e9, 0.3, 7850.0};
  fp::TetMesh mesh = fp::box_mesh(0.5, 0.05, 0.05, 40, 4, 4);
  const fp::NodeGraph graph = fp::NodeGraph::build(mesh);
  const auto geometry = fp::element_geometries(mesh);
  const fp::SparseMatrix k = fp::assemble_stiffness(mesh, graph, geometry, steel);
  const fp::SparseMatrix m_s = fp::assemble_scalar_mass(mesh, graph, geometry, steel.density, fp::MassScheme::consistent);
  const flexbody::format::MassProperties mass = fp::mass_properties(m_s, mesh.nodes);
  const fp::RowMatrixX3d nodes = mesh.nodes.rowwise() - mass.center_of_mass_input.transpose();
  std::vector<int> root;
  for (Eigen::Index i = 0; i < nodes.rows(); ++i)
    if (mesh.nodes(i, 0) == 0.0) root.push_back(static_cast<int>(i));
  Eigen::Index tip = 0;
  (mesh.nodes.rowwise() - Eigen::RowVector3d(0.5, 0.025, 0.025)).rowwise().norm().minCoeff(&tip);
  std::printf("beam: %ld nodes, %ld DOFs, %zu root nodes; %d steps of %.0e s\n\n", static_cast<long>(nodes.rows()),
              static_cast<long>(3 * nodes.rows()), root.size(), static_cast<int>(kEnd / kStep + 0.5), kStep);

  std::ofstream csv(argv[1]);
  csv << "body,modes,coordinates,us_per_step,iterations_per_step,max_tip_error_relative\n";
  std::printf("%-14s %6s %12s %14s %12s %18s\n", "body", "modes", "coordinates", "us per step", "iterations",
              "tip error (rel.)");

  // The reference: every root node held.
  const fr::BodyModel full = fr::full_order_model(fp::full_from_upper(k), fp::full_from_upper(m_s), nodes);
  Run reference;
  {
    fr::System system;
    const int b = system.add_body("beam", full, fr::BodyState{});
    const Eigen::VectorXd q0 = system.initial_coordinates();
    for (int i : root) hold(system, fr::node_marker(full, b, "beam", i), q0, "root " + std::to_string(i));
    reference = integrate(system, b, fr::node_marker(full, b, "beam", tip));
  }
  const double y0 = nodes(tip, 1);
  double largest = 0.0;
  for (double y : reference.tip_y) largest = std::max(largest, std::abs(y - y0));
  std::printf("%-14s %6s %12ld %14.1f %12.2f %18s\n", "full order", "-", static_cast<long>(full.coordinate_count()),
              reference.microseconds_per_step, reference.iterations_per_step, "(reference)");
  csv << "full_order,," << full.coordinate_count() << ',' << reference.microseconds_per_step << ','
      << reference.iterations_per_step << ",0\n";

  for (int fixed_modes : {1, 2, 4, 8, 16, 32}) {
    fp::RigidInterface clamp;
    clamp.nodes = Eigen::Map<const Eigen::VectorXi>(root.data(), static_cast<Eigen::Index>(root.size()));
    for (int i : root) clamp.reference_point += nodes.row(i).transpose() / static_cast<double>(root.size());
    fp::CraigBamptonOptions options;
    options.fixed_interface_modes = fixed_modes;
    const fp::CraigBamptonModes cb = fp::craig_bampton_modes(nodes, k, m_s, steel, {clamp}, options);
    flexbody::format::BodyData body;
    body.mass = mass;
    body.mesh.nodes = nodes;
    body.modes.frequencies_hz = cb.frequencies_hz;
    body.modes.upsilon = fp::upsilon_from_modes(cb.vectors);
    body.gcms = fp::gcms_constants(k, m_s, nodes, body.modes.upsilon);
    const fr::BodyModel model = fr::make_body_model(body, std::nullopt, "cb beam");
    fr::System system;
    const int b = system.add_body("beam", model, fr::BodyState{});
    const Eigen::VectorXd q0 = system.initial_coordinates();
    for (const Eigen::RowVector3d& corner : {Eigen::RowVector3d(0, 0, 0), Eigen::RowVector3d(0, 0.05, 0), Eigen::RowVector3d(0, 0, 0.05)}) {
      Eigen::Index i = 0;
      (mesh.nodes.rowwise() - corner).rowwise().norm().minCoeff(&i);
      hold(system, fr::node_marker(model, b, "beam", i), q0, "clamp " + std::to_string(i));
    }
    const Run run = integrate(system, b, fr::node_marker(model, b, "beam", tip));
    double error = 0.0;
    for (std::size_t s = 0; s < run.tip_y.size(); ++s) error = std::max(error, std::abs(run.tip_y[s] - reference.tip_y[s]));
    error /= largest;
    // One interface: its six constraint modes are the rigid motions, so the basis is the fixed-interface modes.
    const int modes = static_cast<int>(model.modes);
    std::printf("%-14s %6d %12ld %14.1f %12.2f %18.3g\n", "craig-bampton", modes,
                static_cast<long>(model.coordinate_count()), run.microseconds_per_step, run.iterations_per_step, error);
    csv << "craig_bampton," << modes << ',' << model.coordinate_count() << ',' << run.microseconds_per_step << ','
        << run.iterations_per_step << ',' << error << '\n';
  }
  return 0;
}
