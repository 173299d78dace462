#include "publish_stage.hpp"

#include "pose_record.hpp"
#include "throttle.hpp"

#include "handtrack/common/clock.hpp"
#include "logging.hpp"

#include <fmt/format.h>

namespace handtrack::daemon {

PublishStage::PublishStage(ipc::PoseRingWriter& ring, PipelineTally& tally, StageWatch& watch, IntervalStats& stats)
    : ring_(ring), tally_(tally), watch_(watch), stats_(stats) {}

void PublishStage::step(const Frame& f) {
  watch_.busy(Stage::kPublish, f.seq, monotonic_ns());
  if (f.malformed) {
    tally_.skipped.fetch_add(1, std::memory_order_relaxed);
    watch_.idle(Stage::kPublish);
    return;
  }
  if (f.empty) tally_.empty_frames.fetch_add(1, std::memory_order_relaxed);
  ipc::FrameRecord& p = record_;
  p.frame = f.seq;
  p.capture_ns = f.capture_ns;
  p.grab_ms = ms_between(f.capture_ns, f.grab_end_ns);
  p.preprocess_ms = ms_between(f.preprocess_start_ns, f.preprocess_end_ns);
  p.optimize_ms = ms_between(f.optimize_start_ns, f.optimize_end_ns);
  fill_hands(f.output, p);
  // publish_ms: from the end of optimization to the record going out (hand-over + filling).
  p.publish_ms = ms_between(f.optimize_end_ns, monotonic_ns());
  ring_.publish(p);
  const int64_t end_ns = monotonic_ns();
  tally_.published.fetch_add(1, std::memory_order_relaxed);
  tally_.last_publish_ns.store(end_ns, std::memory_order_relaxed);
  const TrackingState state = frame_state(f.output);
  tally_.tracking_state.store(static_cast<int32_t>(to_ipc(state)), std::memory_order_relaxed);
  stats_.add({.grab_ms = p.grab_ms,
              .preprocess_ms = p.preprocess_ms,
              .optimize_ms = p.optimize_ms,
              .publish_ms = ms_between(f.optimize_end_ns, end_ns),
              .latency_ms = ms_between(f.capture_ns, end_ns)});
  log_state_change(state, end_ns);
  watch_.idle(Stage::kPublish);
}

// State changes at info, at most once a second (with how many happened in between).
void PublishStage::log_state_change(TrackingState state, int64_t now_ns) {
  const auto code = static_cast<int32_t>(to_ipc(state));
  if (code == logged_state_) return;
  ++state_changes_;
  if (now_ns - state_logged_ns_ < Throttle::kIntervalNs) return;
  log().info("hand: {}{}", to_string(state),
             state_changes_ > 1 ? fmt::format(" ({} state changes since the last message)", state_changes_) : "");
  logged_state_ = code;
  state_changes_ = 0;
  state_logged_ns_ = now_ns;
}

}  // namespace handtrack::daemon
