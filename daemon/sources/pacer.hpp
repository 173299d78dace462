#pragma once
// Plays a recording or the virtual camera at its own frame rate: frame i is due at start + i/fps.
// When the consumer falls more than two frames behind, the schedule restarts from now instead of
// bursting to catch up (a recording plays like a camera would deliver it).
#include "handtrack/common/clock.hpp"

#include <chrono>
#include <cstdint>
#include <ctime>

namespace handtrack::daemon {

class Pacer {
 public:
  void start(double fps) {
    period_ns_ = fps > 0.0 ? static_cast<int64_t>(1e9 / fps) : 0;
    next_ns_ = monotonic_ns();
  }
  // Waits until the next frame is due. False (after sleeping `timeout`) when it is due later.
  bool wait(std::chrono::milliseconds timeout) {
    if (period_ns_ == 0) return true;
    const int64_t now = monotonic_ns();
    if (now - next_ns_ > 2 * period_ns_) next_ns_ = now;
    const int64_t limit = now + std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count();
    const bool due = next_ns_ <= limit;
    sleep_until(due ? next_ns_ : limit);
    if (due) next_ns_ += period_ns_;
    return due;
  }

 private:
  static void sleep_until(int64_t ns) {
    timespec ts{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
    }
  }
  int64_t period_ns_ = 0;
  int64_t next_ns_ = 0;
};

}  // namespace handtrack::daemon
