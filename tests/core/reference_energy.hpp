#pragma once
// The plain references of E_sim (paper eq. 6, and with a coverage cap) and E_hand (energy.hpp) and their gradients.
// E_sim's: every model Gaussian against every image Gaussian of DepthInput::gaussians, libm exp,
// the chain rule one point at a time. It is the straightforward implementation SimilarityTerm
// started from; the optimised term (DepthInput::mixture slices, SIMD pair sums, one pass through
// the kinematic chain) must give the same values and stay several times faster
// (test_energy_kernel.cpp, handtrack-kernels-bench).

#include "handtrack/core/energy.hpp"

namespace handtrack::reference {

// E_sim with `factor` kDepth or kLabel, and the coverage cap c (0: none); adds dE_sim/dTheta into
// *gradient when not null.
double similarity(const HandModel& model, const PosedHand& hand, const DepthInput& input, SimilarityFactor factor,
                  double label_radius_mm, PoseGradient* gradient, double coverage_cap = 0.0);

// E_hand: every model Gaussian against every Gaussian of `other`, overlap_3d (libm exp, no cut-off),
// the chain rule one point at a time; adds dE_hand/dTheta into *gradient when not null.
double inter_hand(const HandModel& model, const PosedHand& hand, const HandObstacle& other, PoseGradient* gradient);

}  // namespace handtrack::reference
