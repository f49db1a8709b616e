// work_precision_bench: speed against error of the improved GCMS and of the FFRF (the same body file's modes, issue
// 14) on scenes with large rotations, against the unreduced improved ACF of the same mesh at a tight step.
//
//   work_precision_bench SCENE OUTPUT.csv [--quick]
//
// SCENE: pendulum | slider-crank | plate | rotor (see scene_*() below). For every formulation, number of modes and step size it runs the
// scene once and records the CPU time per simulated second and the errors of the scene's quantities of interest,
// sampled every `sample` seconds, against the reference:
//   tip: the largest distance of a marked node from the reference's over the run [m], and relative to the largest
//        distance the reference's node travels;
//   reaction: the joint's reaction force averaged over each sample interval (the impulse over the interval divided by
//        its length: the ringing of modes no model resolves is not a quantity of interest), largest difference
//        relative to the reference's largest.
// Every run uses the integrator's defaults but the step (ρ∞ 0.9, Newton tolerance 1e-6, stabilised index 2). The GCMS
// and the mean-axis FFRF at the scene's largest number of modes run also under error control (step: auto) at each of
// the scene's tolerances; their step_s is the mean step.
#include "work_precision_scenes.hpp"

#include "flexbody/runtime/generalized_alpha.hpp"
#include "flexbody/runtime/system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <string>

namespace fr = flexbody::runtime;
using namespace work_precision;

namespace {

// One run: fixed steps of `step`, or under error control (tolerance > 0 [m per step]) from a first step of `step`
// with max_step end / 10 (fbsim's defaults for a scene with a row every `sample`), each sample's time reached exactly.
History run(const Scene& scene, Built& b, double step, double tolerance = 0.0) {
  fr::GeneralizedAlphaOptions options;
  options.step = step;
  if (tolerance > 0.0) {
    options.error_tolerance = tolerance;
    options.max_step = scene.end / 10.0;
  }
  History h;
  const std::clock_t start = std::clock();
  try {
    fr::GeneralizedAlpha integrator(b.system, options);
    const long per_sample = std::lround(scene.sample / step), samples = std::lround(scene.end / scene.sample);
    auto reaction = [&] {
      if (!b.joint) return Eigen::Vector3d(Eigen::Vector3d::Zero());
      const fr::JointReaction r = b.system.joint_reaction(*b.joint, integrator.time(), integrator.coordinates(), integrator.multipliers());
      return b.moment ? r.moment : r.force;
    };
    Eigen::Vector3d previous = reaction();
    for (long j = 1; j <= samples; ++j) {
      const double t_sample = static_cast<double>(j) * scene.sample;
      Eigen::Vector3d impulse = Eigen::Vector3d::Zero();
      auto advance = [&] {
        const double before = integrator.time();
        if (tolerance > 0.0) integrator.step_toward(t_sample);
        else integrator.step();
        const Eigen::Vector3d now = reaction();
        impulse += 0.5 * (integrator.time() - before) * (previous + now);
        previous = now;
        ++h.steps;
      };
      if (tolerance > 0.0)
        while (integrator.time() < t_sample) advance();
      else
        for (long k = 0; k < per_sample; ++k) advance();
      h.tip.push_back(fr::marker_position(b.tip, b.system.body_coordinates(integrator.coordinates(), b.body)));
      h.reaction.push_back(impulse / scene.sample);
    }
    h.iterations_per_step = static_cast<double>(integrator.total_iterations()) / static_cast<double>(h.steps);
    h.factorizations_per_step = static_cast<double>(integrator.factorizations()) / static_cast<double>(h.steps);
    h.rejected = integrator.rejected_steps();
  } catch (const std::exception& e) {
    h.failed = true;
    h.why = e.what();
  }
  h.cpu_seconds = static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
  return h;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: work_precision_bench pendulum|slider-crank|plate|rotor OUTPUT.csv [--quick]\n");
    return 2;
  }
  const std::string which = argv[1];
  const bool quick = argc > 3 && std::string(argv[3]) == "--quick";
  Scene scene;
  if (which == "pendulum") scene = scene_pendulum(quick);
  else if (which == "plate") scene = scene_plate(quick);
  else if (which == "rotor") scene = scene_rotor(quick);
  else if (which == "slider-crank") scene = scene_slider_crank(quick);
  else {
    std::fprintf(stderr, "work_precision_bench: unknown scene '%s' (pendulum, slider-crank, plate, rotor)\n", which.c_str());
    return 2;
  }
  std::ofstream csv(argv[2]);
  csv << "scene,formulation,modes,coordinates,step_s,error_tolerance_m,steps,rejected_steps,cpu_s_per_simulated_s,"
         "iterations_per_step,matrices_per_step,tip_error_m,tip_error_relative,reaction_error_relative,failed\n";

  const auto reference_built = scene.build(Kind::full_order, 0);
  const History reference = run(scene, *reference_built, scene.reference_step);
  if (reference.failed) {
    std::fprintf(stderr, "work_precision_bench: the reference failed: %s\n", reference.why.c_str());
    return 1;
  }
  double travel = 0.0, largest_reaction = 0.0;
  for (std::size_t j = 0; j < reference.tip.size(); ++j) {
    travel = std::max(travel, (reference.tip[j] - reference.tip.front()).norm());
    largest_reaction = std::max(largest_reaction, reference.reaction[j].norm());
  }
  // The reference's own error, estimated from the same model at twice its step: for a second-order method the error
  // at h is about |x(2h) − x(h)| / 3. Errors of the reduced models below it are not resolved.
  double reference_tip = 0.0, reference_reaction = 0.0;
  {
    const auto coarse_built = scene.build(Kind::full_order, 0);
    const History coarse = run(scene, *coarse_built, 2.0 * scene.reference_step);
    if (coarse.failed) {
      std::fprintf(stderr, "work_precision_bench: the reference at twice its step failed: %s\n", coarse.why.c_str());
      return 1;
    }
    for (std::size_t j = 0; j < reference.tip.size(); ++j) {
      reference_tip = std::max(reference_tip, (coarse.tip[j] - reference.tip[j]).norm() / 3.0);
      reference_reaction = std::max(reference_reaction, (coarse.reaction[j] - reference.reaction[j]).norm() / 3.0);
    }
  }
  const long coordinates = reference_built->system.coordinate_count();
  std::printf("%s: reference (full order, %ld coordinates) at h = %.3g s: %.1f s CPU, %.2f iterations and %.3f "
              "factorizations per step, travel %.3g m\n", scene.name.c_str(), coordinates, scene.reference_step,
              reference.cpu_seconds, reference.iterations_per_step, reference.factorizations_per_step, travel);
  std::printf("  its own error (|x(2h) - x(h)| / 3): tip %.3g m = %.3g of the travel, reaction %.3g of the largest\n",
              reference_tip, reference_tip / travel, largest_reaction > 0.0 ? reference_reaction / largest_reaction : 0.0);
  csv << scene.name << ",full_order,," << coordinates << ',' << scene.reference_step << ",0,"
      << std::lround(scene.end / scene.reference_step) << ",0," << reference.cpu_seconds / scene.end << ','
      << reference.iterations_per_step << ',' << reference.factorizations_per_step << ',' << reference_tip << ','
      << reference_tip / travel << ',' << (largest_reaction > 0.0 ? reference_reaction / largest_reaction : 0.0)
      << ",0\n";
  std::printf("%-10s %5s %10s %9s %14s %10s %8s %12s %12s %12s\n", "model", "modes", "step [s]", "", "CPU s / sim s",
              "iter/step", "mat/step", "tip [m]", "tip (rel)", "reaction");
  // A run's row: step_s is the mean step under error control (tolerance > 0).
  auto record = [&](Kind kind, int modes, double step, double tolerance) {
    const auto built = scene.build(kind, modes);
    const History h = run(scene, *built, step, tolerance);
    double tip = 0.0, reaction = 0.0;
    if (!h.failed)
      for (std::size_t j = 0; j < h.tip.size(); ++j) {
        tip = std::max(tip, (h.tip[j] - reference.tip[j]).norm());
        reaction = std::max(reaction, (h.reaction[j] - reference.reaction[j]).norm());
      }
    const double reaction_relative = largest_reaction > 0.0 ? reaction / largest_reaction : 0.0;
    const double mean_step = tolerance > 0.0 && h.steps > 0 ? scene.end / static_cast<double>(h.steps) : step;
    std::printf("%-10s %5d %10.3g %9s %14.4g %10.2f %8.3f %12.3g %12.3g %12.3g%s\n", name_of(kind), modes, mean_step,
                tolerance > 0.0 ? (std::to_string(h.rejected) + " again").c_str() : "", h.cpu_seconds / scene.end,
                h.iterations_per_step, h.factorizations_per_step, tip, tip / travel, reaction_relative,
                h.failed ? ("  FAILED: " + h.why.substr(0, 80)).c_str() : "");
    if (tolerance > 0.0) std::printf("%-10s %5s (step: auto, error_tolerance %.3g m)\n", "", "", tolerance);
    csv << scene.name << ',' << name_of(kind) << ',' << modes << ',' << built->system.coordinate_count() << ','
        << mean_step << ',' << tolerance << ',' << h.steps << ',' << h.rejected << ',' << h.cpu_seconds / scene.end
        << ',' << h.iterations_per_step << ',' << h.factorizations_per_step << ',' << tip << ',' << tip / travel << ','
        << reaction_relative << ',' << (h.failed ? 1 : 0) << '\n';
    std::fflush(stdout);
  };
  for (const Kind kind : scene.kinds) {
    for (const int modes : scene.modes)
      for (const double step : scene.steps) record(kind, modes, step, 0.0);
    if (kind == Kind::ffrf_interface) continue;  // error control on the GCMS and the mean-axis FFRF
    for (const double tolerance : scene.tolerances) record(kind, scene.modes.back(), scene.sample / 100.0, tolerance);
  }
  return 0;
}
