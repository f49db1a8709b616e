#pragma once
// flexbody/preprocess/interfaces.hpp: interfaces (named sets of surface nodes where a joint or a force
// acts) and their markers (formulations.md, "The Method": constraints and markers: a marker's position is a row of Y,
// its small rotation a 3 x 3 n_f matrix on ξ̄; both linear in q, so point joints have constant Jacobians).

#include "flexbody/format/body_data.hpp"
#include "flexbody/preprocess/cad_surface.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

#include <string>
#include <variant>
#include <vector>

namespace flexbody::preprocess {

/// Surface nodes within `tolerance` of the plane through `point` with normal `normal`.
struct PlaneSelector {
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitX();
  double tolerance = 0.0;  ///< [m]; 0: the default (kDefaultSelectorTolerance of the part's size)
};
/// Surface nodes within `tolerance` of the cylinder of `radius` around the axis through `point` along
/// `direction` (a bore or a shaft seat).
struct CylinderSelector {
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), direction = Eigen::Vector3d::UnitZ();
  double radius = 0.0;
  double tolerance = 0.0;
};
/// Surface nodes inside the axis-aligned box [min, max].
struct BoxSelector {
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();
};
/// The mesh triangles of CAD surfaces, by tag (`fbprep list-surfaces` lists the tags).
struct SurfaceSelector {
  std::vector<int> tags;
};
/// The mesh triangles of the surfaces in a gmsh physical group of dimension 2 (.geo, .msh).
struct GroupSelector {
  std::string name;
};
using Selector = std::variant<PlaneSelector, CylinderSelector, BoxSelector, SurfaceSelector, GroupSelector>;

/// The default selector tolerance as a fraction of the part's bounding-box diagonal: CAD surface nodes
/// lie on their surface to OpenCASCADE's 1e-7 mm, far inside it; mesh sizes are far outside it.
inline constexpr double kDefaultSelectorTolerance = 1e-6;

/// The selector with every length (points, radius, tolerance, box corners) multiplied by `factor`.
[[nodiscard]] Selector scaled(const Selector& selector, double factor);

/// One interface as a body spec asks for it, in the input frame. build_interfaces takes metres;
/// PrepOptions takes the input's length unit (that of --mesh-size) and converts.
/// One rbe2 interface: its nodes move rigidly with 6 DOFs (translation and small rotation about
/// `reference_point`).
struct RigidInterface {
  Eigen::VectorXi nodes;
  Eigen::Vector3d reference_point = Eigen::Vector3d::Zero();  ///< same frame as the nodes
};

struct InterfaceRequest {
  std::string name;
  Selector select;
  std::string coupling = "rbe3";  ///< "rbe2" or "rbe3"
  std::string kind = "interface";  ///< how errors name it: "interface" or "load point"
};

/// The selected surface patch: the nodes of every boundary triangle whose three nodes the selector
/// takes (or of the CAD surfaces' triangles), each weighted by a third of the area of its selected
/// triangles, normalised to sum 1.
struct SurfacePatch {
  Eigen::VectorXi nodes;  ///< ascending
  Eigen::VectorXd weights;
};

/// Applies `selector` to the surface nodes (`nodes` in the same frame as the selector) or to the CAD
/// surfaces. Throws std::invalid_argument starting with `label` (e.g. "interface 'root'") if nothing, or no
/// surface triangle, is selected, or a surface tag or group does not exist (the message lists the ones that do).
[[nodiscard]] SurfacePatch select_surface_patch(const std::string& label, const Selector& selector,
                                                const RowMatrixX3d& nodes, const RowMatrixX3i& surface_triangles,
                                                const std::vector<CadSurface>& surfaces = {});

/// The marker of a patch: reference point Σ w_i X̄_i, y_row = wᵀ Y (Y = [1, X̄, fields]) and the rotation
/// matrix R (θ̄ = R ξ̄, weighted least-squares rigid fit). `body_nodes` are X̄ (body frame). Throws
/// std::invalid_argument if the nodes lie on a line (their rotation about it is undefined).
[[nodiscard]] format::Interface interface_marker(const std::string& name, const std::string& coupling,
                                                 const SurfacePatch& patch, const RowMatrixX3d& body_nodes,
                                                 const Eigen::MatrixXd& fields);

/// An interface's selected patch, before the modes exist.
struct SelectedInterface {
  std::string name, coupling;
  SurfacePatch patch;
};

/// Selects every requested interface (`input_nodes` in the selectors' frame, metres): names unique and
/// allowed, couplings known, no node in two interfaces. Throws std::invalid_argument naming the interface.
[[nodiscard]] std::vector<SelectedInterface> select_interfaces(const std::vector<InterfaceRequest>& requests,
                                                               const RowMatrixX3d& input_nodes,
                                                               const RowMatrixX3i& surface_triangles,
                                                               const std::vector<CadSurface>& surfaces = {});

/// The area centroid Σ w_i X_i of a patch (in the frame of `nodes`).
[[nodiscard]] Eigen::Vector3d patch_centroid(const SurfacePatch& patch, const RowMatrixX3d& nodes);

/// Every requested interface: selects in the input frame (`body_nodes` + `center_of_mass_input`),
/// checks that no two share a node, and builds the markers. Throws std::invalid_argument naming the
/// interface for an empty selection, an unknown coupling, overlapping interfaces or a duplicate name.
[[nodiscard]] std::vector<format::Interface> build_interfaces(const std::vector<InterfaceRequest>& requests,
                                                              const RowMatrixX3d& body_nodes,
                                                              const Eigen::Vector3d& center_of_mass_input,
                                                              const RowMatrixX3i& surface_triangles,
                                                              const Eigen::MatrixXd& fields,
                                                              const std::vector<CadSurface>& surfaces = {});

}  // namespace flexbody::preprocess
