#pragma once
// Constants of the motions' periodic curves (motions.cpp, two_hand_motions.cpp).
#include <numbers>

namespace handtrack::synth {

inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

}  // namespace handtrack::synth
