#pragma once
// flexbody/preprocess/mass_properties.hpp: rigid-body mass properties from the scalar mass M_s.
//
// With M̄ = M_s ⊗ I3 the total mass is 1ᵀ M_s 1, the first moment 1ᵀ M_s X̄ and the second-moment
// matrix J = X̄ᵀ M_s X̄ (formulations.md, "The Method": nodal fields: the first blocks of G = Yᵀ M_s Y). For linear
// tetrahedra and the consistent mass these integrals are exact for the meshed volume.

#include "flexbody/format/body_data.hpp"
#include "flexbody/preprocess/tet_mesh.hpp"

namespace flexbody::preprocess {

/// Mass [kg], centre of mass [m] in the frame of `nodes`, inertia tensor about the centre of mass
/// [kg m^2] (tr(J) I - J with J the second moments about the centre of mass).
[[nodiscard]] format::MassProperties mass_properties(const SparseMatrix& scalar_mass_upper,
                                                     const RowMatrixX3d& nodes);

}  // namespace flexbody::preprocess
