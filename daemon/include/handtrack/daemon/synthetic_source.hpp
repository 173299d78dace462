#pragma once
// The `synthetic[:MOTION]` source: handtrack::synth's virtual camera as a DepthSource, so that the
// daemon, scripts/demo and the tests run without hardware (like libcamera's vimc).
//
//   synthetic          the seven Dexter 1 motions one after another, options.synthetic_frames each
//   synthetic:MOTION   one motion, played back and forth for ever
//
// Frames are paced at the camera's 60 fps unless options.as_fast_as_possible. Frame i of the
// source is a pure function of (motion, options.synthetic_frames, options.seed, i), so a test can
// render the same frame's ground truth with synthetic_camera_options().

#include "handtrack/daemon/depth_source.hpp"
#include "handtrack/synth/synthetic_camera.hpp"

#include <memory>
#include <string>

namespace handtrack::daemon {

// The SynthOptions the source uses for `motion` (one of synth::kMotionNames).
synth::SynthOptions synthetic_camera_options(const std::string& motion, const SourceOptions& options);

// `motion` empty: cycle through all seven. Throws std::invalid_argument for an unknown motion.
std::unique_ptr<DepthSource> make_synthetic_source(const std::string& motion, const SourceOptions& options);

// `seq:DIR` (SPEC.md "Sequence directory"). A PNG that is missing, corrupt or not of camera.json's
// size is reported as GrabStatus::kError (skipped and counted) with the reason in last_error().
std::unique_ptr<DepthSource> make_sequence_source(const std::string& dir, const SourceOptions& options);

}  // namespace handtrack::daemon
