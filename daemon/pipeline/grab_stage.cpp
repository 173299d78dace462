#include "grab_stage.hpp"

#include "recorder.hpp"

#include "handtrack/common/clock.hpp"
#include "logging.hpp"

#include <algorithm>

namespace handtrack::daemon {

namespace {
constexpr auto kGrabTimeout = std::chrono::milliseconds(100);  // a grab() returns at least this often
constexpr int64_t kReopenIntervalNs = 1'000'000'000;           // live device: open() retries
}  // namespace

GrabStage::GrabStage(const DaemonConfig& config, DepthSource& source, ipc::PoseRingWriter& ring,
                     PipelineTally& tally, StageWatch& watch, Doorbell& bell, Recorder* recorder)
    : config_(config), source_(source), ring_(ring), tally_(tally), watch_(watch), bell_(bell), recorder_(recorder) {}

void GrabStage::set_device_state(ipc::DeviceState state) {
  tally_.device_state.store(static_cast<uint32_t>(state), std::memory_order_relaxed);
  ring_.set_device_state(state);
}

bool GrabStage::start(std::string* why) {
  if (source_.is_live()) {
    set_device_state(ipc::DeviceState::kWaitingForDevice);
    return true;
  }
  if (!source_.open(why)) return false;
  open_ = true;
  const auto cam = source_.camera();
  log().info("{}: {}x{} at {} fps{}", source_.describe(), cam.width, cam.height, cam.fps,
             config_.fast ? ", as fast as possible" : "");
  set_device_state(ipc::DeviceState::kStreaming);
  return true;
}

void GrabStage::close() {
  if (!open_) return;
  source_.close();
  open_ = false;
}

// Opens a live source, at most once every kReopenIntervalNs. True when it is open.
bool GrabStage::open_source() {
  const int64_t now = monotonic_ns();
  if (now < next_open_ns_) {
    bell_.wait(bell_.ticket(), std::min<int64_t>(next_open_ns_ - now, Doorbell::kIdleWaitNs));
    return false;
  }
  watch_.busy(Stage::kGrab, next_seq_, now);
  std::string why;
  const bool opened = source_.open(&why);
  watch_.idle(Stage::kGrab);
  if (!opened) {
    next_open_ns_ = monotonic_ns() + kReopenIntervalNs;
    set_device_state(ipc::DeviceState::kWaitingForDevice);
    if (why != last_open_problem_) log().info("waiting for {}: {}", source_.describe(), why);
    last_open_problem_ = why;
    return false;
  }
  last_open_problem_.clear();
  open_ = true;
  const auto cam = source_.camera();
  log().info("{} opened: {}x{} at {} fps", source_.describe(), cam.width, cam.height, cam.fps);
  set_device_state(ipc::DeviceState::kStreaming);
  return true;
}

GrabStage::Step GrabStage::step(Frame& f) {
  if (config_.max_frames > 0 && next_seq_ >= static_cast<uint64_t>(config_.max_frames)) return Step::kDone;
  if (failed_) {  // a recording whose source failed: idle (the heartbeat goes on) until stopped
    bell_.wait(bell_.ticket(), Doorbell::kIdleWaitNs);
    return Step::kNothing;
  }
  if (!open_ && !open_source()) return Step::kNothing;
  watch_.busy(Stage::kGrab, next_seq_, monotonic_ns());
  const GrabStatus status = source_.grab(f.raw, kGrabTimeout);
  const int64_t now = monotonic_ns();
  watch_.idle(Stage::kGrab);
  switch (status) {
    case GrabStatus::kFrame:
      f.seq = next_seq_++;
      f.capture_ns = f.raw.capture_ns != 0 ? f.raw.capture_ns : now;
      f.grab_end_ns = now;
      // SYNC: acq_rel, decides finished() with `completed` (pipeline_tally.hpp).
      if (tally_.captured.fetch_add(1, std::memory_order_acq_rel) == 0) {
        tally_.first_capture_ns.store(f.capture_ns, std::memory_order_relaxed);
      }
      if (recorder_ != nullptr) recorder_->offer(f.raw, f.seq);
      return Step::kFrame;
    case GrabStatus::kTimeout:
      return Step::kNothing;
    case GrabStatus::kEndOfStream:
      log().info("{}: end of stream after {} frames", source_.describe(), next_seq_);
      return Step::kDone;
    case GrabStatus::kDisconnected:
      log().warn("{}: device lost{}{}; waiting for it to come back", source_.describe(),
                 source_.last_error().empty() ? "" : ": ", source_.last_error());
      source_.close();
      open_ = false;
      next_open_ns_ = now + kReopenIntervalNs / 2;
      set_device_state(ipc::DeviceState::kWaitingForDevice);
      return Step::kNothing;
    case GrabStatus::kFailed:
      source_.close();
      open_ = false;
      set_device_state(ipc::DeviceState::kError);
      if (source_.is_live()) {
        next_open_ns_ = now + kReopenIntervalNs;
        log().error("{}: {}; reopening it", source_.describe(), source_.last_error());
      } else {
        failed_ = true;
        log().error("{}: {}; no more frames from it (state error until handtrackd stops)", source_.describe(),
                    source_.last_error());
      }
      return Step::kNothing;
    case GrabStatus::kError: {
      const auto errors = tally_.source_errors.fetch_add(1, std::memory_order_relaxed) + 1;
      if (error_log_.allow(now)) {
        log().warn("{}: bad frame skipped ({} so far): {}", source_.describe(), errors, source_.last_error());
      }
      return Step::kNothing;
    }
  }
  return Step::kNothing;
}

}  // namespace handtrack::daemon
