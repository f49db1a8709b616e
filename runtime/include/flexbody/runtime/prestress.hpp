#pragma once
// flexbody/runtime/prestress.hpp: geometric stiffening at run time (formulations.md, "Geometric Stiffening").
//
// A body file written with `fbprep --geometric-stiffness` holds Ĝ_k, the geometric stiffness of unit prestress case k
// projected on Y = [1, X̄, Ῡ'] (SCHEMA.md, "Geometric stiffness"). At run time the prestress is weighted by the loads
// that cause it, K_g(t) = Σ_k λ_k(t) Ĝ_k, with
//  - centrifugal:xx ... :yz: λ = (ω̄_x², ω̄_y², ω̄_z², ω̄_x ω̄_y, ω̄_x ω̄_z, ω̄_y ω̄_z), ω̄ the body's angular velocity
//    in its own axes;
//  - <interface>:fx ... :mz: the force and the moment about the interface's reference point that the joints (and the
//    forces, torques and springs acting at it) carry into the body there, in body axes.
// Uniform and angular frame accelerations (gravity among them) cause no prestress of a free part beyond what these
// carry (inertia relief balances them). The term adds the second-order strain energy ½ ∫ σ_ij u_k,i u_k,j of the
// displacement measured from the body's frame, ½ ξ̄ᵀ (Σ λ_k Ĝ_k[4:, 4:] ⊗ I3) ξ̄ on a GCMS body: the foreshortening
// that linear kinematics leaves out, whatever the frame, provided λ is the actual prestress.
//
// The weights are held fixed within an evaluation (λ does not vary with the coordinates there): the forces are
// −K_g ξ̄, and the Newton matrix sees K_g only where it is rebuilt from the tangent (the floating frame's; the GCMS's
// constant core does not: a modified Newton iteration in the K_g term).

#include "flexbody/format/body_data.hpp"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace flexbody::runtime {

/// A body's prestress cases, truncated to the fields it keeps.
struct Prestress {
  std::vector<std::string> cases;        ///< as the body file names them
  std::vector<Eigen::MatrixXd> matrices;  ///< Ĝ_k, (4 + n_f) square, one per case
  /// The index of centrifugal case c (format::kCentrifugalCases order) in `cases`, or −1 when the file lacks it.
  std::array<int, 6> centrifugal{-1, -1, -1, -1, -1, -1};
  /// Per interface of the body model (its order): the index of that interface's case l (format::kInterfaceLoadCases
  /// order), or −1.
  std::vector<std::array<int, 6>> interface_cases;
};

/// The prestress cases of `body` for the first n_f fields and the given interfaces (the model's, in its order).
/// Empty (no cases) when the file holds none.
[[nodiscard]] Prestress make_prestress(const format::BodyData& body, Eigen::Index n_f,
                                       const std::vector<format::Interface>& interfaces);

/// The force [N] and the moment about its reference point [N m] that the scene applies at one interface, body axes.
struct InterfaceLoad {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
};

/// λ (one per case, into `weights`) for the angular velocity ω̄ [rad/s] in body axes and the loads at the interfaces
/// (one per interface of the model, in its order).
void prestress_weights(const Prestress& prestress, const Eigen::Vector3d& omega_bar,
                       const std::vector<InterfaceLoad>& loads, Eigen::VectorXd& weights);

/// Σ_k λ_k B_k over the cases with λ_k ≠ 0 into `out` (the size of the B_k; zero when every λ_k is): the weighted
/// geometric stiffness in any projection of the cases (the GCMS fields' blocks, a floating frame's modes).
void weighted_sum(const std::vector<Eigen::MatrixXd>& blocks, const Eigen::VectorXd& weights, Eigen::MatrixXd& out);

}  // namespace flexbody::runtime
