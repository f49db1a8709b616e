#pragma once
// flexbody/preprocess/material.hpp: isotropic linear-elastic materials, by name or by value.

#include "flexbody/format/body_data.hpp"

#include <string_view>

namespace flexbody::preprocess {

using format::Material;

/// Parses "steel", "aluminium" (or "aluminum"), "titanium", or "E=210e9,nu=0.3,rho=7850" (SI, any
/// order, all three required). Throws std::invalid_argument with a message naming the bad part.
[[nodiscard]] Material parse_material(std::string_view text);

/// Throws std::invalid_argument unless E > 0, rho > 0 and -1 < nu < 0.5 (all finite).
void check_material(const Material& material);

/// Lamé's first parameter lambda = E nu / ((1 + nu)(1 - 2 nu)) [Pa].
[[nodiscard]] double lame_lambda(const Material& material);
/// Shear modulus mu = E / (2 (1 + nu)) [Pa].
[[nodiscard]] double shear_modulus(const Material& material);

}  // namespace flexbody::preprocess
