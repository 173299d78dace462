#include "self_calibration.hpp"

#include <atomic>
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
  if (config.background_checks) worker_.emplace("ht-calibrate", [this] { search(); });
}

void SelfCalibration::search() {
  TrackerConfig from = config_;
  from.scale = from_;
  found_ = calibrate_hand_scale(set_.frames(), from).scale;
}

std::optional<HandScale> SelfCalibration::offer(const DepthInput& input, const TrackerOutput& tracked,
                                                const std::optional<HandHint>& hint, const HandScale& current) {
  std::optional<HandScale> found;
  if (worker_) {
    switch (worker_->state()) {
      case IdleWorker::State::kQueued:
      case IdleWorker::State::kRunning:
      case IdleWorker::State::kStop:
        return std::nullopt;
      case IdleWorker::State::kDone:
        if (tracked.hand_id == hand_id_) found = found_;  // else its hand has left: dropped
        worker_->finish();
        break;
      case IdleWorker::State::kIdle:
        break;
    }
  }
  if (tracked.hand_id != hand_id_) {
    hand_id_ = tracked.hand_id;
    set_.clear();
    gathered_ = false;
  }
  // The frame's depth is copied only when the set wants it (one frame in `stride` at most).
  if (!found && !gathered_ && shows_its_size(tracked) && set_.due(tracked, hint)) {
    frame_.camera = input.camera;
    frame_.mirrored = input.mirrored;
    frame_.depth_mm = input.filtered_mm;
    set_.keep(frame_, tracked, *hint);
    if (set_.full()) {
      gathered_ = true;
      from_ = current;
      if (worker_) {
        worker_->submit();
      } else {
        search();
        found = found_;
      }
    }
  }
  if (found) calibrations_taken.fetch_add(1, std::memory_order_relaxed);
  return found;
}

void SelfCalibration::wait() {
  if (worker_) worker_->wait();
}

}  // namespace handtrack
