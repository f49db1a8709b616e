#pragma once
// 2π, between a frequency f [Hz] and its angular frequency ω = 2π f [rad/s] (an eigenvalue of K x = λ M x is ω²).
// One definition for the library: its sources are compiled in batches, where two file-local constants of one name
// collide (cmake/FlexbodyCompileTime.cmake).

#include <numbers>

namespace flexbody::preprocess {

inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

}  // namespace flexbody::preprocess
