// synthetic[:MOTION]: the virtual camera of handtrack::synth as a DepthSource, so that the daemon,
// scripts/demo and the tests run without hardware (like libcamera's vimc).
//
//   synthetic          the seven Dexter 1 motions one after another, options.synthetic_frames each
//   synthetic:MOTION   one motion, played back and forth for ever
//
// Frames are paced at the camera's fps unless options.as_fast_as_possible. Frame i is a pure
// function of (motion, options.synthetic_frames, options.seed, i): synth::live_camera_options()
// renders the same frame with its ground truth.
#include "../source_factories.hpp"

#include "handtrack/synth/synthetic_camera.hpp"

#include "../pacer.hpp"

#include "handtrack/common/clock.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace handtrack::daemon {

namespace {

synth::SynthOptions camera_options(const std::string& motion, const SourceOptions& options) {
  return synth::live_camera_options(motion, options.synthetic_frames, options.seed, options.fps);
}

class SyntheticSource final : public DepthSource {
 public:
  SyntheticSource(const std::string& motion, const SourceOptions& options) : motion_(motion), options_(options) {
    if (motion.empty()) {
      for (const auto name : synth::kMotionNames) {
        cameras_.emplace_back(camera_options(std::string(name), options));
      }
    } else {
      const auto& names = synth::kMotionNames;
      if (std::find(names.begin(), names.end(), motion) == names.end() && !synth::is_two_hand_motion(motion)) {
        std::string known;
        for (const auto name : names) known += (known.empty() ? "" : ", ") + std::string(name);
        for (const auto name : synth::kTwoHandMotionNames) known += ", " + std::string(name);
        throw std::invalid_argument("synthetic:" + motion + ": unknown motion (known: " + known + ")");
      }
      cameras_.emplace_back(camera_options(motion, options));
    }
  }

  [[nodiscard]] std::string describe() const override {
    return motion_.empty() ? "synthetic (all seven motions in turn)" : "synthetic:" + motion_;
  }
  bool open(std::string* /*why*/) override {
    index_ = 0;
    pacer_.start(options_.as_fast_as_possible ? 0.0 : cameras_.front().camera().fps);
    return true;
  }
  void close() override {}

  GrabStatus grab(RawFrame& frame, std::chrono::milliseconds timeout) override {
    if (!pacer_.wait(timeout)) return GrabStatus::kTimeout;
    const auto frames = static_cast<uint64_t>(options_.synthetic_frames);
    // All motions: each plays one pass, then the next; one motion: back and forth for ever.
    auto& camera = cameras_.size() == 1 ? cameras_.front() : cameras_[(index_ / frames) % cameras_.size()];
    const uint64_t local = cameras_.size() == 1 ? index_ : index_ % frames;
    camera.render(static_cast<int>(local % (uint64_t{1} << 30)), rendered_);
    const auto& depth = rendered_.depth;
    frame.camera = depth.camera;
    frame.depth_raw.resize(depth.depth_mm.size());  // no reallocation once sized
    const double per_unit = 1.0 / depth.camera.depth_scale_mm;
    for (size_t i = 0; i < depth.depth_mm.size(); ++i) {
      const double d = depth.depth_mm[i];
      frame.depth_raw[i] = std::isfinite(d) && d > 0.0
                               ? static_cast<uint16_t>(std::clamp(std::lround(d * per_unit), 0L, 65535L))
                               : uint16_t{0};
    }
    // Captured when the frame is complete, as a camera delivers it: rendering is the synthetic
    // camera's exposure, not the tracker's latency.
    frame.capture_ns = monotonic_ns();
    frame.frame_number = index_++;
    return GrabStatus::kFrame;
  }

  [[nodiscard]] CameraIntrinsics camera() const override { return cameras_.front().camera(); }
  [[nodiscard]] bool is_live() const override { return false; }

 private:
  std::string motion_;
  SourceOptions options_;
  std::vector<synth::SyntheticCamera> cameras_;
  synth::SynthFrame rendered_;
  Pacer pacer_;
  uint64_t index_ = 0;
};

}  // namespace

std::unique_ptr<DepthSource> make_synthetic_source(const std::string& motion, const SourceOptions& options) {
  return std::make_unique<SyntheticSource>(motion, options);
}

}  // namespace handtrack::daemon
