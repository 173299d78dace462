#pragma once
// Throttle: at most one warning a second for a condition that can repeat every frame (STYLE.md:
// never log per frame in steady state).
//
// Thread roles: thread-bound (one stage's thread).
#include <cstdint>

namespace handtrack::daemon {

class Throttle {
 public:
  static constexpr int64_t kIntervalNs = 1'000'000'000;

  // True when a message may go out at `now_ns`; false within a second of the last one.
  bool allow(int64_t now_ns) {
    if (now_ns - last_ns_ < kIntervalNs) return false;
    last_ns_ = now_ns;
    return true;
  }

 private:
  int64_t last_ns_ = 0;
};

}  // namespace handtrack::daemon
