#include "optimize_stage.hpp"

#include "handtrack/common/clock.hpp"
#include "logging.hpp"

namespace handtrack::daemon {

static_assert(kMaxHands == 2, "run_slots() shares a frame's work between two hand slots");

OptimizeStage::OptimizeStage(const TrackerConfig& config, CameraRoll roll, TrackerReload& reload,
                             RequestMailbox& request, StageWatch& watch, bool side, std::function<void()> side_setup)
    : reload_(reload), request_(request), watch_(watch), roll_(roll) {
  tracker_.emplace(config);
  request_.put(tracker_->request());  // the first frames: every hand slot free, up to max_hands
  fit_side_ = [this] { tracker_->fit(1, *side_inputs_); };
  if (side) side_ = std::make_unique<SideThread>(std::move(side_setup));
}

void OptimizeStage::apply_reload() {
  if (const auto g = reload_.generation(); g != tracker_generation_) {
    const TrackerConfig c = reload_.config();
    tracker_.emplace(c);  // SIGHUP only: allocates
    tracker_generation_ = g;
    log().info("tracker parameters reloaded ({} particles x {} iterations, up to {} hands); tracking restarts",
               c.particles, c.optimizer.iterations, tracker_->max_hands());
  }
}

void OptimizeStage::step(Frame& f) {
  f.optimize_start_ns = monotonic_ns();
  watch_.busy(Stage::kOptimize, f.seq, f.optimize_start_ns);
  apply_reload();
  if (f.resolution_changed) tracker_->reset();
  if (f.has_input) {
    const uint32_t fitting = tracker_->begin(f.inputs);
    side_inputs_ = &f.inputs;
    run_slots(fitting, side_.get(), fit_side_, [&](int s) { tracker_->fit(s, f.inputs); });
    f.output = tracker_->finish();
    turn_to_camera(roll_, &f.output);
  } else {
    tracker_->reset();
    f.output = HandsOutput{};
  }
  // What the next frames need (per hand: which of left and right, the hints, the last pose).
  request_.put(tracker_->request());
  f.optimize_end_ns = monotonic_ns();
  watch_.idle(Stage::kOptimize);
}

}  // namespace handtrack::daemon
