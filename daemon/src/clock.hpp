#pragma once
// CLOCK_MONOTONIC in nanoseconds: the time base of capture_ns / publish_ns (SPEC.md "Shared memory").
#include <cstdint>
#include <ctime>

namespace handtrack::daemon {

inline int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

inline float ms_between(int64_t from_ns, int64_t to_ns) { return static_cast<float>(to_ns - from_ns) * 1e-6F; }

}  // namespace handtrack::daemon
