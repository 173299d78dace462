#pragma once
// The synthetic source's camera options, to render (with ground truth) exactly the frames that
// handtrackd's `synthetic:MOTION` source delivers with `options`.
#include "handtrack/daemon/depth_source.hpp"
#include "handtrack/synth/synthetic_camera.hpp"

#include <string>

namespace handtrack::daemon {

inline synth::SynthOptions synthetic_source_options(const std::string& motion, const SourceOptions& options = {}) {
  return synth::live_camera_options(motion, options.synthetic_frames, options.seed, options.fps);
}

}  // namespace handtrack::daemon
