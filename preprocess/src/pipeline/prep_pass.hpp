#pragma once
// One fbprep pass from the input to the body file, in stages (fbprep_pipeline.cpp: run_pass calls them in order and
// times all but the body frame and the interfaces): the mesh, the FE matrices, the body frame, the interfaces and load
// cases, the modes, the GCMS constants, the stress modes, the body file. Each stage reads what the ones before it left
// in the PrepPass and fills its part of the summary. flexbody::preprocess's own, not installed.

#include "flexbody/format/body_data.hpp"
#include "flexbody/preprocess/fbprep_pipeline.hpp"
#include "flexbody/preprocess/gmsh_import.hpp"
#include "flexbody/preprocess/interfaces.hpp"

#include <Eigen/Core>

#include <fmt/format.h>

#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

namespace flexbody::preprocess {

/// What the stages of one pass hand on to each other.
struct PrepPass {
  PrepPass(const PrepOptions& o, PrepSummary& s) : options(o), summary(s), input_name(o.input.filename().string()) {}

  const PrepOptions& options;
  PrepSummary& summary;
  std::string input_name;  ///< the input's file name, which the numerical stages' errors begin with
  ImportedMesh imported;
  SparseMatrix stiffness, scalar_mass;      ///< K̄ and M_s, in the input frame's node order
  format::BodyData body;                    ///< the body file's content, filled stage by stage
  std::vector<SelectedInterface> selected;  ///< the interfaces and load points, in the order requested
  Eigen::MatrixXd static_loads;             ///< the load points' unit loads (3 n_n x k), whose static corrections join
  Eigen::MatrixXd prestress_loads;          ///< the geometric stiffness's load cases (3 n_n x p; empty without)
  Eigen::MatrixXd prestress_responses;      ///< their inertia-relieved static responses (after the modes)
  Eigen::MatrixXd mode_vectors;             ///< the modes (3 n_n x k): free-free, or Craig-Bampton's

  /// The nodes in the input frame (the corners first for quadratic tetrahedra).
  [[nodiscard]] const RowMatrixX3d& input_nodes() const {
    return imported.quadratic ? imported.quadratic->nodes : imported.mesh.nodes;
  }
  [[nodiscard]] Eigen::Index node_count() const { return input_nodes().rows(); }

  /// run() with its error named by the input and the stage: out of memory, or the message of what it threw (an
  /// std::invalid_argument keeps its type: an impossible request, exit code 2).
  template <class Run>
  auto in_stage(const char* stage, Run&& run) const {
    try {
      return run();
    } catch (const std::bad_alloc&) {
      throw std::runtime_error(fmt::format("{}: out of memory in the {} stage", input_name, stage));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("{}: {}", input_name, e.what()));
    } catch (const std::exception& e) {
      throw std::runtime_error(fmt::format("{}: {}", input_name, e.what()));
    }
  }
};

/// The geometry imported and meshed (gmsh_import.hpp), the mesh's counts and quality (prep_pass_mesh.cpp).
void mesh_stage(PrepPass& pass);
/// K̄ and M_s, and the mass properties (prep_pass_mesh.cpp).
void assembly_stage(PrepPass& pass);
/// The mesh in the body frame (origin at the centre of mass, the input's axes) and its boundary (prep_pass_mesh.cpp).
void body_frame_stage(PrepPass& pass);
/// The interfaces and load points selected on the mesh, the load points' unit loads, and the geometric stiffness's
/// load cases when asked for (prep_pass_mesh.cpp).
void interface_stage(PrepPass& pass);
/// Free-free modes with their error estimate, or Craig-Bampton modes, and the prestress responses
/// (prep_pass_modes.cpp). With `refine`, a first frequency estimated beyond options.error_target stops the pass: the
/// second mesh's sizes go to *refine, and the stage returns false.
[[nodiscard]] bool modes_stage(PrepPass& pass, std::shared_ptr<const MeshSizeField>* refine);
/// The improved GCMS's constant blocks (fields, G, K̂), the interfaces' markers and the geometric stiffness
/// (prep_pass_body.cpp).
void gcms_stage(PrepPass& pass);
/// The stress modes at the output regions' nodes (prep_pass_body.cpp).
void recovery_stage(PrepPass& pass);
/// The body file, with its provenance (prep_pass_body.cpp).
void write_stage(PrepPass& pass);

}  // namespace flexbody::preprocess
