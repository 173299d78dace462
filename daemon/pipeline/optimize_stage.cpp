#include "optimize_stage.hpp"

#include "handtrack/common/clock.hpp"
#include "logging.hpp"

namespace handtrack::daemon {

OptimizeStage::OptimizeStage(const TrackerConfig& config, TrackerReload& reload, RequestMailbox& request,
                             StageWatch& watch)
    : reload_(reload), request_(request), watch_(watch) {
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
  if (f.has_input) {
    f.output = tracker_->optimise(f.inputs);
  } else {
    tracker_->reset();
    f.output = TrackerOutput{};
  }
  f.scale = tracker_->config().scale;
  // What the next frames need (both hands and no hint after a loss: the next frame starts afresh).
  request_.put(tracker_->request());
  f.optimize_end_ns = monotonic_ns();
  watch_.idle(Stage::kOptimize);
}

}  // namespace handtrack::daemon
