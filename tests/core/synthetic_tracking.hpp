#pragma once
// What the tracking tests on the synthetic motions share: the paper's configuration (Sec. 7:
// 2 particles x 10 iterations), the shipped part forest for late fusion, and the rendering of the
// seven motions as the accuracy table (scripts/eval-synthetic) renders them.
#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/tracker.hpp"
#include "handtrack/synth/synthetic_camera.hpp"

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace handtrack::testing {

inline constexpr int kSequenceFrames = 300;

// The shipped part forest, loaded once per test program.
inline const PartForest& shipped_forest() {
  static const PartForest forest = PartForest::load(shipped_forest_path().value());
  return forest;
}

inline TrackerConfig paper_config(EnergyMode mode) {
  TrackerConfig config;
  config.mode = mode;
  config.particles = 2;
  config.optimizer.iterations = 10;
  return config;
}

// The subjects (synthetic seeds: hand size, noise) the tracking tests assert over. One subject
// decides nothing: a change to the image mixture moves single sequences by tens of millimetres
// either way, and a test of one seed passed or failed by the subject it happened to use
// (docs/TRACKER.md, "Clean depth"). So the tests assert shares and means over three.
inline constexpr std::array<uint64_t, 3> kSubjectSeeds = {7, 8, 9};

// 320x240, sensor noise on, body background: the frames of the accuracy table.
inline synth::SyntheticCamera motion_camera(std::string_view motion, uint64_t seed = kSubjectSeeds[0]) {
  synth::SynthOptions options;
  options.motion = std::string(motion);
  options.frames = kSequenceFrames;
  options.noise = true;
  options.seed = seed;
  return synth::SyntheticCamera(options);
}

// One rendered hand tracked by a Tracker (every frame), scored from frame `from_frame` on: the mean
// fingertip error over the scored frames with a pose, how many had one, and how many of those were
// reported as the hand shown. Runs of several subjects pool with add(): the mean is then over
// every posed frame of them all.
struct OneHandRun {
  double error_sum_mm = 0.0;  // the frames' mean fingertip errors, summed over the posed frames
  int posed = 0;
  int reported_as_shown = 0;

  [[nodiscard]] double mean_error_mm() const { return posed > 0 ? error_sum_mm / posed : 1e9; }
  void add(const OneHandRun& other) {
    error_sum_mm += other.error_sum_mm;
    posed += other.posed;
    reported_as_shown += other.reported_as_shown;
  }
};

// The mean distance of a tracked pose's fingertips from the frame's true ones, mm.
inline double fingertip_error_mm(const TrackerOutput& out, const synth::SynthFrame& frame) {
  double e = 0.0;
  for (size_t t = 0; t < kNumFingers; ++t) e += (out.fingertips[t] - *frame.fingertips[t]).norm();
  return e / kNumFingers;
}

inline OneHandRun track_one_hand(const synth::SynthOptions& options, const TrackerConfig& config,
                                 const PixelLabeller* labeller = nullptr, int from_frame = 0) {
  synth::SyntheticCamera camera(options);
  Tracker tracker(config);
  const Handedness shown = options.hand == synth::Handedness::kLeft ? Handedness::kLeft : Handedness::kRight;
  OneHandRun run;
  synth::SynthFrame frame;
  for (int i = 0; i < options.frames; ++i) {
    camera.render(i, frame);
    const TrackerOutput out = tracker.track(frame.depth, labeller);
    if (i < from_frame || out.state == TrackingState::kNoHand) continue;
    ++run.posed;
    run.reported_as_shown += out.handedness == shown ? 1 : 0;
    run.error_sum_mm += fingertip_error_mm(out, frame);
  }
  return run;
}

}  // namespace handtrack::testing
