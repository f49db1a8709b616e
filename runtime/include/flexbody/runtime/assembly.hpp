#pragma once
// flexbody/runtime/assembly.hpp: the initial assembly of a scene. An interface's reference point comes from a mesh,
// so a part placed at its CAD's nominal position is micrometres off its neighbour's; Adams, Simpack and Exudyn close
// such gaps before the first step, and so does this.
//
// Among the rigid coordinates (τ and a = vec(A) of a GCMS body, τ and p of a floating-frame one; deformations stay as
// they are in the body's frame: a GCMS body's ξ turns with A), at the time t = 0 of driven joints, the correction Δq of least kinetic-energy norm ½ Δqᵀ M_r Δq that satisfies every joint row and keeps
// each body rigid (AᵀA = I, pᵀp = 1), found by Gauss-Newton steps on the linearised rows:
//
//   [M_r  J_rᵀ] [Δq]   [ 0 ]
//   [J_r  0   ] [λ ] = [−Φ ],   J_r = ∂Φ/∂q_r,  M_r = G[0:4, 0:4] ⊗ I3 (or the floating frame's M_rr at η = 0).
//
// The mass metric moves a light part rather than a heavy one, and a part by translation rather than rotation where
// either closes a gap. The joints' directions (revolute and prismatic axes, fixed frames) were fixed from the initial
// state when the joints were made, so their rows hold already and stay held.

#include "flexbody/runtime/system.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace flexbody::runtime {

struct AssemblyOptions {
  /// The largest move a body may make, as a fraction of its size (the bounding-box diagonal of its mesh, or
  /// 2√3 times its radius of gyration for a body without one). A gap that needs more is a modelling error, not
  /// a mesh's rounding, and is refused.
  double tolerance = 0.01;
  int max_iterations = 20;  ///< Gauss-Newton steps before the assembly fails
};

struct AssemblyReport {
  std::vector<double> moves;  ///< per body: the largest displacement of a point of it [m]
  int iterations = 0;         ///< Gauss-Newton steps taken (0: the scene was assembled)
  double largest_gap = 0.0;   ///< the largest joint position residual before [m]
  [[nodiscard]] int most_moved() const;  ///< the body with the largest move (−1 if none)
};

/// A scene that cannot be assembled; `joint` is the index of the joint its message names (System::joints()).
class AssemblyError : public std::invalid_argument {
 public:
  AssemblyError(const std::string& what, std::size_t which) : std::invalid_argument(what), joint(which) {}
  std::size_t joint;
};

/// Moves the system's initial state onto Φ(q, 0) = 0 as above and stores it (System::set_initial_coordinates).
/// Throws AssemblyError (a std::invalid_argument) with one line naming the joint whose gap is largest against its bodies' sizes when a
/// body must move more than tolerance × its size, or when the iteration does not converge (a joint that cannot
/// close: its markers farther apart than the mechanism reaches).
AssemblyReport assemble(System& system, const AssemblyOptions& options = {});

/// A body's size for AssemblyOptions::tolerance [m].
[[nodiscard]] double body_size(const BodyModel& model);

}  // namespace flexbody::runtime
