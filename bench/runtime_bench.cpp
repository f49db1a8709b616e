// runtime_bench: cost per time step of the improved-GCMS runtime against the number of modes, with the
// constant-core Newton solve (formulations.md, "The Method": the constant core) and with the dense Newton matrix, and
// for a chain of flexible bodies. Prints a table and writes CSV for bench/runtime_plot.py.
//
//   runtime_bench OUTPUT.csv [WORK_DIR]
//
// The body is a 1 x 0.05 x 0.03 m steel bar meshed by fbprep (gmsh, 8 mm elements) with 80 free-free modes;
// each model takes its first n_m. A step is one generalized-α step (ρ∞ = 0.9) of a free body oscillating in
// its first mode plus a slow spin, h = 1/50 of the first period.
#include "flexbody/format/body_file.hpp"
#include "flexbody/preprocess/fbprep_pipeline.hpp"
#include "flexbody/runtime/gcms_elastic.hpp"
#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"
#include "kernels/dense_product.hpp"

#include <Eigen/Cholesky>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

namespace fr = flexbody::runtime;
namespace fp = flexbody::preprocess;

namespace {

struct Timing {
  double microseconds_per_step = 0.0;
  double iterations_per_step = 0.0;
  double factorizations_per_step = 0.0;
};

// The three Newton variants: the constant core with the matrix kept across steps (the default), the constant
// core rebuilt every iteration, the dense matrix rebuilt every iteration.
// And the default with the index-3 form (positions only), for the cost of the velocity rows of the stabilised
// index-2 form.
struct Variant {
  const char* name;
  fr::NewtonMatrix matrix;
  bool reuse;
  fr::ConstraintForm form = fr::ConstraintForm::stabilized_index2;
};
constexpr Variant kVariants[] = {{"core_kept", fr::NewtonMatrix::constant_core, true},
                                 {"core_every_iteration", fr::NewtonMatrix::constant_core, false},
                                 {"dense_every_iteration", fr::NewtonMatrix::dense, false},
                                 {"core_kept_index3", fr::NewtonMatrix::constant_core, true, fr::ConstraintForm::index3}};

constexpr int kRuns = 3;

Timing time_steps(const fr::System& system, const Variant& variant, double step, int steps) {
  fr::GeneralizedAlphaOptions options;
  options.newton_matrix = variant.matrix;
  options.reuse_newton_matrix = variant.reuse;
  options.constraints = variant.form;
  options.step = step;
  fr::GeneralizedAlpha integrator(system, options);
  for (int i = 0; i < 5; ++i) integrator.step();  // warm-up (allocations, caches)
  const long before = integrator.total_iterations(), factors = integrator.factorizations();
  // The fastest of 12 chunks of steps/4 steps: the virtual machines this runs on lose time to their neighbours
  // (top shows steal time) in bursts of milliseconds to seconds, which only ever add; the fastest chunk is the
  // code's own cost. A chunk of 500 steps (5 to 20 modes) holds one or two of the kept matrix's rebuilds (about
  // one per 350 steps), so those figures include them; the 100-step chunks of the larger scenes may miss them,
  // which makes those figures up to 2.5 % low.
  const int chunk = std::max(1, steps / 4), chunks = 4 * kRuns;
  double best = std::numeric_limits<double>::infinity();
  for (int run = 0; run < chunks; ++run) {
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < chunk; ++i) integrator.step();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  const double total = static_cast<double>(chunks) * chunk;
  return {1e6 * best / chunk, static_cast<double>(integrator.total_iterations() - before) / total,
          static_cast<double>(integrator.factorizations() - factors) / total};
}

fr::BodyState vibrating(const fr::BodyModel& model) {
  fr::BodyState state;
  state.angular_velocity = Eigen::Vector3d(0.0, 0.0, 1.0);
  state.xi = Eigen::VectorXd::Zero(3 * model.field_count());
  for (Eigen::Index f = 0; f < model.field_count(); ++f)
    state.xi.segment<3>(3 * f) = 1e-3 * model.mode_coefficients.block<1, 3>(f, 0).transpose();
  return state;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: runtime_bench OUTPUT.csv [WORK_DIR]\n");
    return 2;
  }
  const std::filesystem::path work = argc > 2 ? argv[2] : std::filesystem::temp_directory_path() / "flexbody_runtime_bench";
  std::filesystem::create_directories(work);
  std::ofstream(work / "bar.geo") << "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 0.05, 0.03};\n";
  fp::PrepOptions prep;
  prep.input = work / "bar.geo";
  prep.output = work / "bar.fbh5";
  prep.mesh.unit = fp::LengthUnit::metre;
  prep.mesh.mesh_size = 0.008;
  prep.mesh.order = 1;  // the mesh of its recorded results; the step's cost depends on the modes, not the mesh
  prep.modes.modes = 80;
  prep.output_regions = std::vector<fp::OutputRegionRequest>{};
  const fp::PrepSummary summary = fp::run_fbprep(prep);
  const flexbody::format::BodyData body = flexbody::format::read_body_file(prep.output);
  std::printf("body: %ld nodes, %ld DOFs, 80 modes (%.1f .. %.1f Hz)\n\n", static_cast<long>(summary.nodes),
              static_cast<long>(summary.dofs), body.modes.frequencies_hz(0), body.modes.frequencies_hz(79));

  std::ofstream csv(argv[1]);
  csv << "scene,modes,fields,coordinates,newton,us_per_step,iterations_per_step,factorizations_per_step\n";
  std::printf("%-8s %5s %6s %6s  %22s %22s %22s %22s\n", "scene", "n_m", "n_f", "n_q", "core, kept [us (it)]",
              "core, fresh [us (it)]", "dense, fresh [us (it)]", "core, kept, index 3");
  auto report = [&](const char* scene, int n_m, Eigen::Index n_f, Eigen::Index n_q, const fr::System& system,
                    double step, int steps) {
    std::printf("%-8s %5d %6ld %6ld ", scene, n_m, static_cast<long>(n_f), static_cast<long>(n_q));
    for (const Variant& variant : kVariants) {
      const bool slow = variant.matrix == fr::NewtonMatrix::dense || !variant.reuse;
      const Timing t = time_steps(system, variant, step, slow && n_m > 20 ? std::max(20, steps / 4) : steps);
      std::printf("  %12.1f (%4.2f, %4.2f)", t.microseconds_per_step, t.iterations_per_step, t.factorizations_per_step);
      csv << scene << ',' << n_m << ',' << n_f << ',' << n_q << ',' << variant.name << ',' << t.microseconds_per_step
          << ',' << t.iterations_per_step << ',' << t.factorizations_per_step << '\n';
    }
    std::printf("\n");
  };
  const double step = 1.0 / body.modes.frequencies_hz(0) / 50.0;
  for (int n_m : {5, 10, 20, 40, 80}) {
    const fr::BodyModel model = fr::make_body_model(body, n_m, "bar");
    fr::System system;
    system.add_body("bar", model, vibrating(model));
    report("free", n_m, model.field_count(), model.coordinate_count(), system, step, n_m <= 20 ? 2000 : 400);
  }

  // Where a 20-mode step's time goes: the kernels of one Newton iteration, timed alone.
  {
    const fr::BodyModel model = fr::make_body_model(body, 20, "bar");
    const fr::BodyState state = vibrating(model);
    const Eigen::Index n = 3 * model.field_count();
    // The Newton core's inverse (as ConstantCoreNewton keeps it) and a right-hand side.
    const Eigen::MatrixXd core_inverse =
        Eigen::LLT<Eigen::MatrixXd>(Eigen::MatrixXd::Identity(n, n) + model.stiffness * 1e-8).solve(Eigen::MatrixXd::Identity(n, n));
    const Eigen::VectorXd rhs = Eigen::VectorXd::Random(n);
    fr::System system;
    system.add_body("bar", model, state);
    const Eigen::VectorXd q = system.initial_coordinates(), v = system.initial_velocities();
    auto per_call = [](int reps, auto&& f) {
      double best = std::numeric_limits<double>::infinity(), sink = 0.0;
      for (int run = 0; run < kRuns; ++run) {
        const auto start = std::chrono::steady_clock::now();
        for (int i = 0; i < reps; ++i) sink += f();
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      }
      const double us = 1e6 * best / reps;
      return sink == 12345.678 ? -us : us;  // keeps the work from being optimized away
    };
    const Eigen::Matrix3d a = state.orientation;
    std::printf("\n20 modes (3 n_f = %ld), one Newton iteration's kernels [us per call]:\n", static_cast<long>(n));
    std::printf("  elastic forces (K_hat xi_bar), plain K_hat %6.1f  (System keeps K_hat on aligned columns)\n",
                per_call(4000, [&] { return fr::elastic_forces(model.stiffness, a, state.xi).energy; }));
    Eigen::VectorXd product(n);
    std::printf("  core product C^-1 r, Eigen's product      %7.1f\n",
                per_call(4000, [&] { return Eigen::VectorXd(core_inverse * rhs)(0); }));
    std::printf("  core product C^-1 r, the runtime's kernel %7.1f  (runtime/src/kernels: the machine's widest vectors)\n",
                per_call(4000, [&] {
                  fr::detail::dense_product(core_inverse, rhs.data(), product.data());
                  return product(0);
                }));
    const fr::detail::PaddedMatrix padded(core_inverse);
    std::printf("  the same on 64-byte-aligned columns      %8.1f  (PaddedMatrix, as the runtime keeps C^-1 and K_hat)\n",
                per_call(4000, [&] {
                  padded.multiply(rhs.data(), product.data());
                  return product(0);
                }));
    std::printf("  mass product (G x I3) qdd               %8.1f\n", per_call(4000, [&] { return system.mass_product(q, v)(0); }));
    std::printf("  all applied and elastic forces           %8.1f\n", per_call(4000, [&] { return system.forces(0.0, q, v)(0); }));
    std::printf("  elastic tangent without the xi-xi block  %8.1f  (a matrix rebuild)\n", per_call(500, [&] {
                  return fr::elastic_tangent(model.stiffness, a, state.xi, false).aa(0, 0);
                }));
  }

  // A chain of four flexible bars (10 modes each) hanging from a revolute joint and linked by revolute joints at
  // their end nodes, released from horizontal under gravity.
  {
    const fr::BodyModel model = fr::make_body_model(body, 10, "bar");
    fr::System system;
    // The corners (x_min, y_min, z_min) and (x_max, y_min, z_min) of the bar: gmsh puts nodes at the box's vertices.
    const Eigen::RowVector3d low = model.nodes.colwise().minCoeff(), high = model.nodes.colwise().maxCoeff();
    Eigen::Index left = 0, right = 0;
    (model.nodes.rowwise() - low).rowwise().norm().minCoeff(&left);
    (model.nodes.rowwise() - Eigen::RowVector3d(high.x(), low.y(), low.z())).rowwise().norm().minCoeff(&right);
    const double length = model.nodes(right, 0) - model.nodes(left, 0);
    for (int k = 0; k < 4; ++k) {
      fr::BodyState state;
      state.position = Eigen::Vector3d(k * length, 0, 0) - model.nodes.row(left).transpose();
      std::string name = "bar";  // appended: GCC 12 warns falsely on "literal" + std::string&&
      name += std::to_string(k);
      system.add_body(name, model, state);
    }
    const Eigen::VectorXd q0 = system.initial_coordinates();
    for (int k = 0; k < 4; ++k) {
      const fr::Marker here = fr::node_marker(model, k, "bar", left);
      const Eigen::VectorXd qk = system.body_coordinates(q0, k);
      if (k == 0) {
        system.add_joint(fr::make_joint("j0", fr::JointType::revolute, here, fr::ground_marker(fr::marker_position(here, qk)),
                                        Eigen::Vector3d::UnitZ(), qk, Eigen::VectorXd()));
      } else {
        // The previous bar's right corner and this bar's left corner coincide (the same mesh, shifted by its length).
        const fr::Marker there = fr::node_marker(model, k - 1, "bar", right);
        std::string name = "j";
        name += std::to_string(k);
        system.add_joint(fr::make_joint(name, fr::JointType::revolute, here, there,
                                        Eigen::Vector3d::UnitZ(), qk, system.body_coordinates(q0, k - 1)));
      }
    }
    system.set_gravity(Eigen::Vector3d(0, -9.81, 0));
    report("chain4", 10, model.field_count(), system.coordinate_count(), system, 1e-4, 500);
  }
  return 0;
}
