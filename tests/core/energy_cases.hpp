#pragma once
// Realistic inputs for the energy kernels (test_energy_kernel.cpp, handtrack-kernels-bench):
// synthetic 320x240 frames of the Dexter 1 motions with sensor noise and a body behind the hand,
// built into C_I by DepthInputBuilder (segmentation hinted by the true pose, as while tracking)
// with the ground-truth part labels on the leaves, and poses near and off the true pose.

#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/pose.hpp"
#include "handtrack/synth/synthetic_camera.hpp"

#include <cstdint>
#include <vector>

namespace handtrack::testing {

struct EnergyCase {
  synth::SynthFrame frame;
  DepthInput input;                // labelled C_I of the frame
  PoseParams truth;                // the rendered pose
  std::vector<PoseParams> poses;   // truth, then alternately near it and off it
};

// `frames` frames spread over the seven motions, `poses_per_frame` poses each (>= 1).
// Near: +-5 mm, +-0.05 rad global rotation, +-0.1 rad joint angles; off: +-30 mm, +-0.3 rad, +-0.6 rad.
std::vector<EnergyCase> synthetic_energy_cases(int frames, int poses_per_frame, uint64_t seed = 11);

// The segmentation hint the tracker would give with `pose` as its previous pose.
HandHint hint_from_pose(const PoseParams& pose);

}  // namespace handtrack::testing
