// fbprep's first stages (prep_pass.hpp): the mesh, the FE matrices, the interfaces and load cases.
#include "prep_pass.hpp"

#include "flexbody/format/file_digest.hpp"
#include "flexbody/preprocess/assembly.hpp"
#include "flexbody/preprocess/geometric_stiffness.hpp"
#include "flexbody/preprocess/mass_properties.hpp"
#include "flexbody/preprocess/tet10_assembly.hpp"

namespace flexbody::preprocess {

void mesh_stage(PrepPass& pass) {
  const PrepOptions& options = pass.options;
  PrepSummary& summary = pass.summary;
  GmshImportOptions mesh_options = options.mesh;
  mesh_options.progress = options.progress;
  pass.imported = import_tet_mesh(options.input, mesh_options);
  const ImportedMesh& imported = pass.imported;
  summary.input_sha256 = format::sha256_of_file(options.input);
  summary.format = imported.format;
  summary.unit = std::string(to_string(imported.unit));
  summary.unit_reason = imported.unit_reason;
  summary.declared_unit = imported.declared_unit ? std::string(to_string(*imported.declared_unit)) : std::string();
  summary.unit_overrides_declared = imported.unit_overrides_declared;
  summary.volumes = imported.volumes;
  summary.sewn_faces = imported.sewn_faces;
  summary.loose_entities = imported.loose_entities;
  summary.meshed_here = imported.meshed_here;
  summary.mesh_size_m = imported.mesh_size_m;
  summary.mesher = options.mesh.algorithm;
  summary.curved_repair = imported.curved_repair;
  summary.cad_volume_m3 = imported.cad_volume_m3;
  summary.extent_m = imported.extent_m;
  summary.size_warning = imported.size_warning;
  summary.refined_from_m = imported.refined_from_m;
  summary.first_volume_error = imported.first_volume_error;
  // Quadratic tetrahedra (--order 2) number their corners first; every stage below takes all nodes.
  summary.element_order = imported.quadratic ? 2 : 1;
  summary.nodes = pass.node_count();
  summary.elements = imported.mesh.element_count();
  summary.dofs = 3 * pass.node_count();
  summary.quality = imported.quadratic ? mesh_quality(*imported.quadratic) : mesh_quality(imported.mesh);
}

void assembly_stage(PrepPass& pass) {
  const PrepOptions& options = pass.options;
  PrepSummary& summary = pass.summary;
  const ImportedMesh& imported = pass.imported;
  if (options.progress) options.progress(fmt::format("assembling K and M ({} DOFs)", summary.dofs));
  pass.in_stage("assembly", [&] {
    if (imported.quadratic) {  // K̄ by the 4-point rule, the exact consistent M_s (tet10_assembly.hpp)
      Tet10Matrices matrices = assemble_tet10(*imported.quadratic, options.material);
      pass.stiffness = std::move(matrices.stiffness);
      pass.scalar_mass = std::move(matrices.scalar_mass);
      return;
    }
    const TetMesh& mesh = imported.mesh;
    const NodeGraph graph = NodeGraph::build(mesh);  // graph and geometry die here: memory for the modes
    const std::vector<Tet4Geometry> geometry = element_geometries(mesh);
    pass.stiffness = assemble_stiffness(mesh, graph, geometry, options.material);
    pass.scalar_mass = assemble_scalar_mass(mesh, graph, geometry, options.material.density, MassScheme::consistent);
  });
  summary.mass = mass_properties(pass.scalar_mass, pass.input_nodes());
}

void body_frame_stage(PrepPass& pass) {
  const ImportedMesh& imported = pass.imported;
  PrepSummary& summary = pass.summary;
  format::BodyData& body = pass.body;
  body.mesh.nodes = pass.input_nodes().rowwise() - summary.mass.center_of_mass_input.transpose();
  if (imported.quadratic) {
    body.mesh.tets = imported.quadratic->tets;
    body.mesh.element_order = 2;
    body.mesh.surface_triangles = boundary_triangles(*imported.quadratic);
  } else {
    body.mesh.tets = imported.mesh.tets;
    body.mesh.surface_triangles = boundary_triangles(imported.mesh);
  }
  summary.surface_triangles = body.mesh.surface_triangles.rows();
}

void interface_stage(PrepPass& pass) {
  const PrepOptions& options = pass.options;
  PrepSummary& summary = pass.summary;
  const format::BodyData& body = pass.body;
  const Eigen::Index node_count = pass.node_count();
  // Interfaces are selected now (Craig-Bampton needs their nodes); their markers follow the GCMS fields.
  // Load points are rbe3 interfaces too (the runtime applies their loads there).
  pass.selected = pass.in_stage("interfaces", [&] {
    std::vector<InterfaceRequest> in_metres = options.interfaces;
    for (const LoadPointRequest& p : options.load_points) in_metres.push_back({p.name, p.select, "rbe3", "load point"});
    for (InterfaceRequest& request : in_metres) request.select = scaled(request.select, metres_per(pass.imported.unit));
    std::vector<SelectedInterface> chosen =
        select_interfaces(in_metres, pass.input_nodes(), body.mesh.surface_triangles, pass.imported.surfaces);
    // A patch whose nodes lie on a line has no defined rotation (and would leave Craig-Bampton's interior
    // singular): refuse it now, before the modes, naming the interface.
    for (const SelectedInterface& s : chosen)
      (void)interface_marker(s.name, s.coupling, s.patch, body.mesh.nodes, Eigen::MatrixXd(node_count, 0));
    return chosen;
  });

  // The load points' unit loads, whose static corrections join the modes.
  std::vector<LoadPoint> load_points;
  for (const LoadPointRequest& request : options.load_points)
    for (const SelectedInterface& s : pass.selected)
      if (s.name == request.name)
        load_points.push_back(
            {s.name, s.patch.nodes, s.patch.weights, patch_centroid(s.patch, body.mesh.nodes), request.loads});
  pass.static_loads = pass.in_stage("interfaces", [&] { return unit_load_vectors(body.mesh.nodes, load_points); });
  summary.static_loads = unit_load_labels(load_points);

  // The geometric stiffness's load cases (geometric_stiffness.hpp): the six centrifugal ones and a unit force and
  // moment at every interface, each balanced by inertia relief.
  if (!options.geometric_stiffness) return;
  std::vector<LoadPoint> at_interfaces;
  for (const SelectedInterface& s : pass.selected)
    at_interfaces.push_back({s.name, s.patch.nodes, s.patch.weights, patch_centroid(s.patch, body.mesh.nodes)});
  pass.prestress_loads = pass.in_stage("geometric stiffness", [&] {
    const Eigen::MatrixXd interface_loads = unit_load_vectors(body.mesh.nodes, at_interfaces);
    Eigen::MatrixXd loads(3 * node_count, 6 + interface_loads.cols());
    loads << centrifugal_unit_loads(body.mesh.nodes, pass.scalar_mass), interface_loads;
    return loads;
  });
  for (const char* c : kCentrifugalCases) summary.prestress_cases.push_back(std::string("centrifugal:") + c);
  for (const std::string& label : unit_load_labels(at_interfaces)) summary.prestress_cases.push_back(label);
}

}  // namespace flexbody::preprocess
