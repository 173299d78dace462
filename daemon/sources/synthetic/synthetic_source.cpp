// synthetic[:MOTION]: the virtual camera of handtrack::synth as a DepthSource, so that the daemon,
// scripts/demo and the tests run without hardware (like libcamera's vimc).
//
//   synthetic          the seven Dexter 1 motions one after another, options.synthetic_frames each
//   synthetic:MOTION   one motion, played back and forth for ever
//
// Frames are paced at the camera's fps unless options.as_fast_as_possible. Frame i is a pure
// function of (motion, options.synthetic_frames, options.seed, i): synth::live_camera_options()
// renders the same frame with its ground truth. With options.synthetic_prerender the frames of one
// period (a motion's back-and-forth pass, or all seven motions in turn) are rendered when the
// source is made, and replayed from memory for ever: a frame then costs the host no CPU, as a
// camera's does, and only the first period's noise repeats.
#include "../source_factories.hpp"

#include "handtrack/synth/synthetic_camera.hpp"

#include "../pacer.hpp"

#include "handtrack/common/clock.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
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
    if (options.synthetic_prerender) prerender();
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
    if (period_ == 0) {
      render(index_, frame.depth_raw);
    } else {  // no reallocation once sized
      const size_t n = pixels();
      frame.depth_raw.resize(n);
      std::memcpy(frame.depth_raw.data(), prerendered_.data() + (index_ % period_) * n, n * sizeof(uint16_t));
    }
    frame.camera = cameras_.front().camera();
    // Captured when the frame is complete, as a camera delivers it: rendering is the synthetic
    // camera's exposure, not the tracker's latency.
    frame.capture_ns = monotonic_ns();
    frame.frame_number = index_++;
    return GrabStatus::kFrame;
  }

  [[nodiscard]] CameraIntrinsics camera() const override { return cameras_.front().camera(); }
  [[nodiscard]] bool is_live() const override { return false; }

 private:
  // The most memory prerendering may take (1 GiB: 7000 frames at 320x240).
  static constexpr size_t kMaxPrerenderBytes = size_t{1} << 30;

  [[nodiscard]] size_t pixels() const {
    const auto& cam = cameras_.front().camera();
    return static_cast<size_t>(cam.width) * static_cast<size_t>(cam.height);
  }

  // Frame `index` in raw depth units (no reallocation once `raw` is sized).
  void render(uint64_t index, std::vector<uint16_t>& raw) {
    const auto frames = static_cast<uint64_t>(options_.synthetic_frames);
    // All motions: each plays one pass, then the next; one motion: back and forth for ever.
    auto& camera = cameras_.size() == 1 ? cameras_.front() : cameras_[(index / frames) % cameras_.size()];
    const uint64_t local = cameras_.size() == 1 ? index : index % frames;
    camera.render(static_cast<int>(local % (uint64_t{1} << 30)), rendered_);
    const auto& depth = rendered_.depth;
    raw.resize(depth.depth_mm.size());
    const double per_unit = 1.0 / depth.camera.depth_scale_mm;
    for (size_t i = 0; i < depth.depth_mm.size(); ++i) {
      const double d = depth.depth_mm[i];
      raw[i] = std::isfinite(d) && d > 0.0 ? static_cast<uint16_t>(std::clamp(std::lround(d * per_unit), 0L, 65535L))
                                           : uint16_t{0};
    }
  }

  // Frames 0 .. period - 1 into prerendered_: one motion plays 0..N-1, N-2..1 (2N - 2 frames),
  // all motions one pass each (7N).
  void prerender() {
    const auto frames = static_cast<uint64_t>(options_.synthetic_frames);
    const uint64_t period = cameras_.size() == 1 ? 2 * (frames - 1) : frames * cameras_.size();
    const size_t bytes = period * pixels() * sizeof(uint16_t);
    if (bytes > kMaxPrerenderBytes) {
      throw std::invalid_argument("synthetic.prerender: " + std::to_string(period) + " frames would take " +
                                  std::to_string(bytes >> 20) + " MiB (at most " +
                                  std::to_string(kMaxPrerenderBytes >> 20) + "); lower synthetic.frames");
    }
    prerendered_.resize(period * pixels());
    std::vector<uint16_t> raw;
    for (uint64_t i = 0; i < period; ++i) {
      render(i, raw);
      std::copy(raw.begin(), raw.end(), prerendered_.begin() + static_cast<std::ptrdiff_t>(i * pixels()));
    }
    period_ = period;
  }

  std::string motion_;
  SourceOptions options_;
  std::vector<synth::SyntheticCamera> cameras_;
  synth::SynthFrame rendered_;
  Pacer pacer_;
  uint64_t index_ = 0;
  std::vector<uint16_t> prerendered_;  // period_ frames of pixels() raw depths each
  uint64_t period_ = 0;                // 0: each frame rendered when it is due
};

}  // namespace

std::unique_ptr<DepthSource> make_synthetic_source(const std::string& motion, const SourceOptions& options) {
  return std::make_unique<SyntheticSource>(motion, options);
}

}  // namespace handtrack::daemon
