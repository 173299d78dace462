#pragma once
// StageWatch: what each stage is doing, for the watchdog. A stage marks itself busy on a frame
// before work that may block (a device read, an optimization) and idle when it waits for input;
// the control thread asks whether any stage has been busy on one frame for too long.
//
// Thread roles: busy()/idle() of stage S from S's thread only; stalled()/describe() from any
// thread. Thread-safe.
#include "handtrack/daemon/config.hpp"

#include <array>
#include <atomic>
#include <cstdint>
#include <string>

namespace handtrack::daemon {

class StageWatch {
 public:
  void busy(Stage stage, uint64_t frame, int64_t now_ns);
  void idle(Stage stage);
  // True when some stage has been busy on one frame for longer than `limit_ns` at `now_ns`.
  [[nodiscard]] bool stalled(int64_t now_ns, int64_t limit_ns) const;
  // "optimize busy on frame 20 for 2.1 s, ..." for every stage busy longer than `limit_ns`.
  [[nodiscard]] std::string describe_stalls(int64_t now_ns, int64_t limit_ns) const;

 private:
  // SYNC: relaxed throughout. Each word is written by one stage and read by the control thread,
  // which needs a recent value, not an order with other memory: a stall lasts seconds.
  struct alignas(64) Activity {
    std::atomic<int64_t> busy_since_ns{0};  // 0: waiting for input (legitimately idle)
    std::atomic<uint64_t> frame{0};
  };
  std::array<Activity, kNumStages> activity_{};
};

}  // namespace handtrack::daemon
