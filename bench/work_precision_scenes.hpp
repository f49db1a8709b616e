#pragma once
// The scenes of work_precision_bench (bench/work_precision_bench.cpp): how a body is modelled, a scene built for one
// model, and the four scenes with their references' steps.

#include "flexbody/runtime/system.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace work_precision {

namespace fr = flexbody::runtime;

// How a body is modelled.
enum class Kind { full_order, gcms, ffrf_mean_axis, ffrf_interface };
inline const char* name_of(Kind k) {
  switch (k) {
    case Kind::full_order: return "full_order";
    case Kind::gcms: return "gcms";
    case Kind::ffrf_mean_axis: return "ffrf";
    case Kind::ffrf_interface: return "ffrf_root";
  }
  return "?";
}

// A scene built for one model: its system, the marked node, and the joint whose reaction is watched (if any).
struct Built {
  fr::System system;
  int body = 0;
  fr::Marker tip;
  std::optional<std::size_t> joint;
  bool moment = false;  ///< watch the joint's moment instead of its force
};

struct Scene {
  std::string name;
  double end = 0.0, sample = 0.0, reference_step = 0.0;
  std::vector<double> steps;
  std::vector<int> modes;
  /// Error control's runs (step: auto), at the largest of `modes`: their tolerances [m per step].
  std::vector<double> tolerances;
  std::vector<Kind> kinds;
  std::function<std::unique_ptr<Built>(Kind, int)> build;
};

// Samples at t = j * sample: the tip's position and the reaction averaged over ((j − 1) sample, j sample].
struct History {
  std::vector<Eigen::Vector3d> tip, reaction;
  double cpu_seconds = 0.0, iterations_per_step = 0.0, factorizations_per_step = 0.0;
  long steps = 0, rejected = 0;  ///< accepted steps; under error control, steps taken again for their error
  bool failed = false;
  std::string why;
};

Scene scene_pendulum(bool quick);
Scene scene_slider_crank(bool quick);
Scene scene_plate(bool quick);
Scene scene_rotor(bool quick);

}  // namespace work_precision
