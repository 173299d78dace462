#pragma once
// CLOCK_MONOTONIC in nanoseconds: the time base of every *_ns field (capture_ns, publish_ns, the
// ring's heartbeat; SPEC.md "Shared memory"), so that times taken in the daemon, the ring and a
// client on the same machine compare directly.
#include <cstdint>
#include <ctime>

namespace handtrack {

inline int64_t monotonic_ns() noexcept {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

// Milliseconds from one monotonic_ns() time to another (the ring's per-stage timings).
inline float ms_between(int64_t from_ns, int64_t to_ns) noexcept { return static_cast<float>(to_ns - from_ns) * 1e-6F; }

}  // namespace handtrack
