#include "self_calibration.hpp"

#include "idle_thread.hpp"

#include <cmath>

namespace handtrack {

namespace {
std::atomic<uint64_t> calibrations_taken{0};  // self_calibrations_taken()

// A frame shows the hand's size where the hand faces the camera, palm or back (its normal within
// 35 deg of the ray to the palm), so that the fingers' length and the palm's width lie across the
// image, and the four fingers are open: their flexion (three joints each) under kOpenRad a finger
// on average. Not each finger under a bound: a model too long for the hand curls some fingers to fit
// it (a hand 15 % smaller, adbadd: the little finger 2-3 rad), and would never calibrate; a fist
// (about 3 rad a finger), or two fingers folded as fingercount folds them, stays out.
constexpr double kFacingCos = 0.82;  // cos 35 deg
constexpr double kOpenRad = 0.8;

bool shows_its_size(const TrackerOutput& tracked) {
  if (std::abs(tracked.palm_normal.dot(tracked.palm_centre.normalized())) < kFacingCos) return false;
  double flexion = 0.0;
  for (int f = kIndex; f < kNumFingers; ++f) {
    for (int dof = 1; dof < 4; ++dof) flexion += tracked.params[angle_param(f, dof)];
  }
  return flexion < (kNumFingers - 1) * kOpenRad;
}
}  // namespace

uint64_t self_calibrations_taken() { return calibrations_taken.load(std::memory_order_relaxed); }

SelfCalibration::SelfCalibration(const TrackerConfig& config)
    : config_(calibration_tracker_config(config)), set_(CalibrationSet::Options{}, input_config(config)) {
  if (config.background_checks) thread_ = std::thread([this] { run(); });
}

SelfCalibration::~SelfCalibration() {
  if (!thread_.joinable()) return;
  state_.store(State::kStop, std::memory_order_release);
  state_.notify_all();
  join_from_idle_class(thread_);  // a search under way finishes first
}

HandScale SelfCalibration::search() const {
  TrackerConfig from = config_;
  from.scale = from_;
  HandScale found = from_;
  found.length = calibrate_hand_scale(set_.frames(), from).scale.length;
  return found;
}

std::optional<HandScale> SelfCalibration::offer(const DepthInput& input, const TrackerOutput& tracked,
                                                const std::optional<HandHint>& hint, const HandScale& current) {
  std::optional<HandScale> found;
  switch (state_.load(std::memory_order_acquire)) {
    case State::kQueued:
    case State::kRunning:
    case State::kStop:
      return std::nullopt;
    case State::kDone:
      if (tracked.hand_id == hand_id_) {
        found = found_;
        calibrations_taken.fetch_add(1, std::memory_order_relaxed);
      }
      state_.store(State::kGathering, std::memory_order_relaxed);
      break;
    case State::kGathering:
      break;
  }
  if (tracked.hand_id != hand_id_) {
    hand_id_ = tracked.hand_id;
    set_.clear();
    gathered_ = false;
  }
  if (found || gathered_ || !shows_its_size(tracked)) return found;
  frame_.camera = input.camera;
  frame_.mirrored = input.mirrored;
  frame_.depth_mm = input.filtered_mm;
  set_.offer(frame_, tracked, hint);
  if (!set_.full()) return std::nullopt;
  gathered_ = true;
  from_ = current;
  if (!thread_.joinable()) {
    calibrations_taken.fetch_add(1, std::memory_order_relaxed);
    return search();
  }
  state_.store(State::kQueued, std::memory_order_release);
  state_.notify_all();
  return std::nullopt;
}

void SelfCalibration::wait() {
  for (State s = state_.load(std::memory_order_acquire); s == State::kQueued || s == State::kRunning;
       s = state_.load(std::memory_order_acquire)) {
    state_.wait(s, std::memory_order_acquire);
  }
}

void SelfCalibration::run() {
  become_idle_class("ht-calibrate");
  for (;;) {
    State s = state_.load(std::memory_order_acquire);
    while (s != State::kQueued && s != State::kStop) {
      state_.wait(s, std::memory_order_acquire);
      s = state_.load(std::memory_order_acquire);
    }
    if (s == State::kStop) return;
    if (!state_.compare_exchange_strong(s, State::kRunning, std::memory_order_acq_rel)) continue;  // stopped
    found_ = search();
    State running = State::kRunning;
    if (state_.compare_exchange_strong(running, State::kDone, std::memory_order_acq_rel)) state_.notify_all();
  }
}

}  // namespace handtrack
