#include "stage_watch.hpp"

#include <fmt/format.h>

namespace handtrack::daemon {

void StageWatch::busy(Stage stage, uint64_t frame, int64_t now_ns) {
  auto& a = activity_[static_cast<size_t>(stage)];
  a.frame.store(frame, std::memory_order_relaxed);
  a.busy_since_ns.store(now_ns, std::memory_order_relaxed);
}

void StageWatch::idle(Stage stage) {
  activity_[static_cast<size_t>(stage)].busy_since_ns.store(0, std::memory_order_relaxed);
}

bool StageWatch::stalled(int64_t now_ns, int64_t limit_ns) const {
  for (const auto& a : activity_) {
    const int64_t since = a.busy_since_ns.load(std::memory_order_relaxed);
    if (since != 0 && now_ns - since > limit_ns) return true;
  }
  return false;
}

std::string StageWatch::describe_stalls(int64_t now_ns, int64_t limit_ns) const {
  std::string out;
  for (int s = 0; s < kNumStages; ++s) {
    const auto& a = activity_[static_cast<size_t>(s)];
    const int64_t since = a.busy_since_ns.load(std::memory_order_relaxed);
    if (since == 0 || now_ns - since < limit_ns) continue;
    if (!out.empty()) out += ", ";
    out += fmt::format("{} busy on frame {} for {:.1f} s", to_string(static_cast<Stage>(s)),
                       a.frame.load(std::memory_order_relaxed), static_cast<double>(now_ns - since) * 1e-9);
  }
  return out;
}

}  // namespace handtrack::daemon
