#pragma once
// Body files' data that the tests build from a mesh of their own, as fbprep would write it.

#include "flexbody/format/body_data.hpp"
#include "test_meshes.hpp"

namespace flexbody::test {

/// The mesh's first `modes` free-free modes with their improved-GCMS constants: nodes moved to the centre of mass,
/// mass properties, frequencies, residuals, Ῡ and the GCMS blocks (no interfaces, regions or stress recovery).
[[nodiscard]] format::BodyData free_free_body(const AssembledMesh& mesh, const preprocess::Material& material, int modes);

}  // namespace flexbody::test
