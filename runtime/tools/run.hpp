#pragma once
// run.hpp: integrates a scene and writes what it asks for (one CSV per output, monitors.csv on request).

#include "scene.hpp"

#include <filesystem>
#include <functional>
#include <string>

namespace flexbody::fbsim {

struct RunSummary {
  long steps = 0;
  long newton_iterations = 0;
  long newton_matrices = 0;  ///< Newton matrices built (factorizations)
  bool sparse = false;       ///< the reduced Newton matrix was factorized sparse (GeneralizedAlpha::sparse)
  double cpu_seconds = 0.0;
  double energy_initial = 0.0, energy_final = 0.0;
  /// max_t |E(t) − E_0| / max_t (kinetic + elastic + spring energy): meaningful for conservative scenes (no
  /// applied forces, torques or damping, whose work it does not count).
  double energy_drift = 0.0;
  double max_constraint_residual = 0.0;  ///< max over the checked steps (every kCheckEvery-th) of |Φ|∞
  double wall_seconds = 0.0;             ///< the whole run: integration, checks and outputs
  double integrator_wall_seconds = 0.0;  ///< GeneralizedAlpha::step alone
  /// Conservative scenes (Scene::conserves), over the checked steps: the largest (E(t) − E_0) / (the largest kinetic +
  /// elastic + spring energy so far), and the largest (|L(t)| − |L_0|) / |L_0| of the angular momentum about the
  /// centre of mass; each denominator at least 1e-9 of the magnitudes of the terms summed (round-off); 0 when not
  /// checked.
  double energy_growth = 0.0, angular_momentum_growth = 0.0;
  /// One line per conservation law that a conservative scene broke by more than kConservationTolerance, and the
  /// integrator's lines about the model's validity (GeneralizedAlpha::warnings), in the order they arose.
  std::vector<std::string> warnings;
  std::size_t conservation_warnings = 0, validity_warnings = 0;  ///< how many of each
  std::vector<std::filesystem::path> files;
};

/// Energies, constraint residuals and momenta are evaluated every kCheckEvery steps and at the last (an evaluation
/// costs about a fifth of a 16-mode step; the drift they watch is slow). Monitor rows evaluate their own. The
/// interval is odd because the instability of generalized-α near ρ∞ = 1 is an oscillation of period 2 h: an even
/// interval samples one phase only (measured: a spinning plate whose energy is 0.8 % high at every other step
/// showed no growth at every 10th).
inline constexpr long kCheckEvery = 9;
/// A conservative scene whose energy grows by more than this fraction of the largest kinetic + elastic + spring
/// energy, or whose angular momentum about the centre of mass grows by more than this fraction of its initial
/// magnitude, gets a warning (on stderr when it happens, in RunSummary::warnings and fbsim --json). Generalized-α
/// with ρ∞ < 1 only dissipates, and with ρ∞ = 1 its energy error oscillates at O((ω h)²), 1e-5 for the rigid
/// pendulum at ω h = 4e-3 (docs/accuracy-and-speed.md).
inline constexpr double kConservationTolerance = 1e-3;

/// Runs the scene to its end time, writing into `directory` (created). Throws runtime::StepFailure (after
/// writing every completed step) when a step fails.
RunSummary run_scene(Scene& scene, const std::filesystem::path& directory,
                     const std::function<void(double)>& progress = {},
                     const std::function<void(const std::string&)>& warn = {});

}  // namespace flexbody::fbsim
