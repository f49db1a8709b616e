#pragma once
// flexbody/preprocess/tet4_element.hpp: the linear tetrahedron, defined with the body file's mesh in
// flexbody/format/tet4_element.hpp (the runtime's full-order body integrates the same element) and named here for
// the preprocessing code.

#include "flexbody/format/tet4_element.hpp"

namespace flexbody::preprocess {

using format::MassScheme;
using format::Tet4Geometry;
using format::tet4_geometry;
using format::tet4_mass_entry;
using format::tet4_stiffness_block;

}  // namespace flexbody::preprocess
