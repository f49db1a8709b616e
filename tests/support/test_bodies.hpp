#pragma once
// Body files' data that the tests build from a mesh of their own, as fbprep would write it.

#include "flexbody/format/body_data.hpp"
#include "test_meshes.hpp"

namespace flexbody::test {

/// The mesh's first `modes` free-free modes with their improved-GCMS constants: nodes moved to the centre of mass,
/// mass properties, frequencies, residuals, Ῡ and the GCMS blocks (no interfaces, regions or stress recovery).
[[nodiscard]] format::BodyData free_free_body(const AssembledMesh& mesh, const preprocess::Material& material, int modes);

/// A soft bar `length` x 0.04 x 0.02 m (E 5e9 Pa, ν 0.3, ρ 1000 kg/m³; `cells` x 2 x 1 Kuhn-split cells) with its
/// first `modes` free-free modes: the runtime tests' flexible body.
[[nodiscard]] format::BodyData soft_bar(double length, int cells, int modes);

}  // namespace flexbody::test
