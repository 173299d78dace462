#include "optimize_stage.hpp"

#include "handtrack/common/clock.hpp"
#include "logging.hpp"

namespace handtrack::daemon {

OptimizeStage::OptimizeStage(const TrackerConfig& config, TrackerReload& reload, HintMailbox& hint,
                             StageWatch& watch)
    : reload_(reload), hint_(hint), watch_(watch) {
  tracker_.emplace(config);
}

void OptimizeStage::apply_reload() {
  if (const auto g = reload_.generation(); g != tracker_generation_) {
    const TrackerConfig c = reload_.config();
    tracker_.emplace(c);  // SIGHUP only: allocates
    tracker_generation_ = g;
    log().info("tracker parameters reloaded ({} particles x {} iterations); tracking restarts", c.particles,
               c.optimizer.iterations);
  }
}

void OptimizeStage::step(Frame& f) {
  f.optimize_start_ns = monotonic_ns();
  watch_.busy(Stage::kOptimize, f.seq, f.optimize_start_ns);
  apply_reload();
  if (f.resolution_changed) tracker_->reset();
  if (f.input != nullptr) {
    f.output = tracker_->optimise(*f.input);
  } else {
    tracker_->reset();
    f.output = TrackerOutput{};
  }
  f.scale = tracker_->config().scale;
  // Hint for the next frames' segmentation (none after a loss: the next frame starts afresh).
  hint_.put(tracker_->hint());
  f.optimize_end_ns = monotonic_ns();
  watch_.idle(Stage::kOptimize);
}

}  // namespace handtrack::daemon
