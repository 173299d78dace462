#pragma once
// What flows between stages besides frames: what the next frame's preprocessing should build
// (optimize -> preprocess) and a reloaded tracker configuration (control thread -> preprocess and
// optimize).
//
// Thread roles: thread-safe (a mutex each; taken once per frame, never contended for long).
#include "handtrack/core/hands_tracker.hpp"

#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>

namespace handtrack::daemon {

// The tracker's request for the next frame (HandsTracker::request(): per hand which of left and
// right, the segmentation hints and the last pose, by which the frame is shared out among the hands): optimize writes after every frame, preprocess reads before
// every frame. A frame preprocessed while the previous one is still being optimized uses the
// request of the one before: that lag of one frame is the price of the overlap.
class RequestMailbox {
 public:
  void put(const HandsRequest& request) {
    std::lock_guard lock(mutex_);
    request_ = request;
  }
  [[nodiscard]] HandsRequest get() const {
    std::lock_guard lock(mutex_);
    return request_;
  }

 private:
  mutable std::mutex mutex_;
  HandsRequest request_;
};

// SIGHUP: the control thread posts a new tracker configuration; each stage that depends on it
// compares the generation it last applied with generation() between two frames and takes the
// new configuration when they differ.
class TrackerReload {
 public:
  explicit TrackerReload(const TrackerConfig& initial) : config_(initial) {}

  void post(const TrackerConfig& config) {
    {
      std::lock_guard lock(mutex_);
      config_ = config;
    }
    // SYNC: release, pairs with generation()'s acquire: a stage that sees the new generation
    // takes the mutex after it and so reads the new configuration (the mutex alone orders the
    // configuration; the counter only saves the lock on the 99.99 % of frames without a reload).
    generation_.fetch_add(1, std::memory_order_release);
  }
  // SYNC: acquire, pairs with post()'s increment.
  [[nodiscard]] uint64_t generation() const { return generation_.load(std::memory_order_acquire); }
  [[nodiscard]] TrackerConfig config() const {
    std::lock_guard lock(mutex_);
    return config_;
  }

 private:
  mutable std::mutex mutex_;
  TrackerConfig config_;
  std::atomic<uint64_t> generation_{0};
};

}  // namespace handtrack::daemon
