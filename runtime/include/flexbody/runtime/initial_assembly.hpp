#pragma once
// flexbody/runtime/initial_assembly.hpp: the initial assembly of a scene. An interface's reference point comes from a
// mesh, so a part placed at its CAD's nominal position is micrometres off its neighbour's; Adams, Simpack and Exudyn
// close such gaps before the first step, and so does this.
//
// Among the rigid coordinates (τ and a = vec(A) of a GCMS body, τ and p of a floating-frame one; deformations stay as
// they are in the body's frame: a GCMS body's ξ turns with A), at the time t = 0 of driven joints, the correction Δq
// of least kinetic-energy norm ½ Δqᵀ M_r Δq that satisfies every joint row and keeps each body rigid (AᵀA = I,
// pᵀp = 1), found by Gauss-Newton steps on the linearised rows:
//
//   [W    J_rᵀ] [Δq]   [ 0 ]
//   [J_r  0   ] [λ ] = [−Φ ],   J_r = ∂Φ/∂q_r,  W = M_r = G[0:4, 0:4] ⊗ I3 (or the floating frame's M_rr at η = 0).
//
// The mass metric moves a light part rather than a heavy one, and a part by translation rather than rotation where
// either closes a gap. The joints' directions (revolute and prismatic axes, fixed frames) were fixed from the initial
// state when the joints were made, so their rows hold already and stay held.
//
// A closed loop with a flexible body in it (a slider-crank whose rod is flexible, pinned at both ends) may not close
// by rigid moves: its rows are independent only through the rod's deformation (a planar loop of revolute joints
// repeats three rows among rigid coordinates, which System::remove_redundant_constraints keeps because the rod can
// bend out of its plane). The deformations of the flexible bodies that lie on a closed loop (ξ with its Tisserand
// rows (Eqs. 77-78), or η) are unknowns too, with the metric
//
//   W = M + K_e / (ε ω₁²),   K_e = ∂²U/∂ξ² = Â K̂ Âᵀ (Eq. 96) or K_ff,   ε = 1e-6,
//
// ω₁ the frequency of the body's first mode: a move along it costs 10⁶ times a rigid move of its size. A
// misfit that rigid moves cannot take is then taken by the least strain energy (the body starts prestressed, as a
// part forced into place does), and any other gap is closed rigidly but for a share of order ε. The full-order
// reference body (full_order.hpp) moves rigidly only.

#include "flexbody/runtime/system.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace flexbody::runtime {

struct InitialAssemblyOptions {
  /// The largest move a body may make, as a fraction of its size (the bounding-box diagonal of its mesh, or
  /// 2√3 times its radius of gyration for a body without one). A gap that needs more is a modelling error, not
  /// a mesh's rounding, and is refused.
  double tolerance = 0.01;
  int max_iterations = 20;  ///< Gauss-Newton steps before the assembly fails
};

struct InitialAssemblyReport {
  std::vector<double> moves;  ///< per body: the largest displacement of a point of it [m], deformation included
  /// per body: the largest displacement of a point by the deformation the assembly gave it [m] (zero but in a closed
  /// loop whose rigid moves could not close it)
  std::vector<double> deformations;
  double strain_energy = 0.0;            ///< the elastic energy the assembly added to the bodies [J]
  int iterations = 0;                    ///< Gauss-Newton steps taken (0: the scene was assembled)
  double largest_gap = 0.0;              ///< the largest joint position residual before [m]
  [[nodiscard]] int most_moved() const;  ///< the body with the largest move (−1 if none)
};

/// A scene that cannot be assembled; `joint` is the index of the joint its message names (System::joints()).
class InitialAssemblyError : public std::invalid_argument {
 public:
  InitialAssemblyError(const std::string& what, std::size_t which) : std::invalid_argument(what), joint(which) {}
  std::size_t joint;
};

/// Moves the system's initial state onto Φ(q, 0) = 0 as above and stores it (System::set_initial_coordinates).
/// Throws InitialAssemblyError (a std::invalid_argument) with one line naming the joint whose gap is largest against
/// its bodies' sizes when a body must move more than tolerance × its size, or when the iteration does not converge (a
/// joint that cannot close: its markers farther apart than the mechanism reaches).
InitialAssemblyReport initial_assembly(System& system, const InitialAssemblyOptions& options = {});

/// A body's size for InitialAssemblyOptions::tolerance [m].
[[nodiscard]] double body_size(const BodyModel& model);

}  // namespace flexbody::runtime
