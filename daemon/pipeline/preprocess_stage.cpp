#include "preprocess_stage.hpp"

#include "handtrack/common/clock.hpp"
#include "logging.hpp"

#include <algorithm>

namespace handtrack::daemon {

static_assert(kMaxHands == 2, "run_slots() shares a frame's work between two hand slots");

PreprocessStage::PreprocessStage(const TrackerConfig& config, CameraRoll roll, TrackerReload& reload,
                                 const RequestMailbox& request, const PartForest* forest, PipelineTally& tally,
                                 StageWatch& watch, bool side, std::function<void()> side_setup)
    : reload_(reload), request_(request), forest_(forest), tally_(tally), watch_(watch),
      input_config_(input_config(config)), roll_(roll) {
  build_side_ = [this] { side_frame_->inputs.build_slot(1, side_frame_->depth, side_request_, forest_); };
  if (side) side_ = std::make_unique<SideThread>(std::move(side_setup));
}

void PreprocessStage::apply_reload() {
  if (const auto g = reload_.generation(); g != input_generation_) {
    input_config_ = input_config(reload_.config());
    input_generation_ = g;
  }
}

void PreprocessStage::step(Frame& f) {
  f.preprocess_start_ns = monotonic_ns();
  watch_.busy(Stage::kPreprocess, f.seq, f.preprocess_start_ns);
  apply_reload();
  if (f.inputs_generation != input_generation_) {
    f.inputs = HandsInputs(input_config_, splitter_);  // SIGHUP only: allocates
    f.inputs_generation = input_generation_;
  }
  f.has_input = false;
  f.empty = false;
  f.malformed = false;
  f.resolution_changed = false;
  const CameraIntrinsics& cam = f.raw.camera;
  const auto n = static_cast<size_t>(std::max(cam.width, 0)) * static_cast<size_t>(std::max(cam.height, 0));
  if (n == 0 || f.raw.depth_raw.size() != n || !(cam.depth_scale_mm > 0.0)) {
    f.malformed = true;
  } else {
    if (cam.width != stream_width_ || cam.height != stream_height_) {
      if (stream_width_ != 0) {
        tally_.resolution_changes.fetch_add(1, std::memory_order_relaxed);
        log().info("resolution changed from {}x{} to {}x{} at frame {}: frame buffers rebuilt, tracking restarts",
                   stream_width_, stream_height_, cam.width, cam.height, f.seq);
        f.resolution_changed = true;
      }
      stream_width_ = cam.width;
      stream_height_ = cam.height;
    }
    // Raw units to mm; pixels inside the working volume (Sec. 4: 150..600 mm); upright.
    DepthImage& mm = roll_ == CameraRoll::k0 ? f.depth : camera_depth_;
    const size_t in_volume =
        mm.assign_raw(cam, f.raw.depth_raw, static_cast<float>(input_config_.near_mm),
                      static_cast<float>(input_config_.far_mm));
    if (roll_ != CameraRoll::k0) turn_upright(camera_depth_, roll_, &f.depth);
    if (in_volume == 0) {
      f.empty = true;
    } else {
      side_request_ = request_.get();
      const uint32_t slots = f.inputs.share(f.depth, side_request_);
      side_frame_ = &f;
      run_slots(slots, side_.get(), build_side_,
                [&](int s) { f.inputs.build_slot(s, f.depth, side_request_, forest_); });
      f.has_input = true;
    }
  }
  f.preprocess_end_ns = monotonic_ns();
  watch_.idle(Stage::kPreprocess);
}

}  // namespace handtrack::daemon
