#pragma once
// What the tracking tests on the synthetic motions share: the paper's configuration (Sec. 7:
// 2 particles x 10 iterations), the shipped part forest for late fusion, and the rendering of the
// seven motions as the accuracy table (scripts/eval-synthetic) renders them.
#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/tracker.hpp"
#include "handtrack/synth/synthetic_camera.hpp"

#include <filesystem>
#include <string>
#include <string_view>

namespace handtrack::testing {

inline constexpr int kSequenceFrames = 300;

inline TrackerConfig paper_config(EnergyMode mode) {
  TrackerConfig config;
  config.mode = mode;
  config.particles = 2;
  config.optimizer.iterations = 10;
  return config;
}

// 320x240, sensor noise on, body background, seed 7: the frames of the accuracy table.
inline synth::SyntheticCamera motion_camera(std::string_view motion) {
  synth::SynthOptions options;
  options.motion = std::string(motion);
  options.frames = kSequenceFrames;
  options.noise = true;
  options.seed = 7;
  return synth::SyntheticCamera(options);
}

}  // namespace handtrack::testing
