#pragma once
// IntervalStats: the statistics of one interval (PipelineConfig::stats_interval_ms): frame rate,
// mean stage times and the capture-to-publish latency's p50/p99. At the end of each interval
// they go into the ring header (clients see them), to the debug log and to the control thread
// (STATUS=).
//
// Thread roles: add() and maybe_publish() from the publishing thread (publish, or the single
// thread); last() from any thread. Allocates only in the constructor.
#include "pipeline_tally.hpp"

#include "handtrack/ipc/pose_ring_writer.hpp"

#include <cstdint>
#include <mutex>
#include <vector>

namespace handtrack::daemon {

// One published frame's stage times (ms) and its capture-to-publish latency.
struct FrameTimes {
  float grab_ms = 0;
  float preprocess_ms = 0;
  float optimize_ms = 0;
  float publish_ms = 0;
  float latency_ms = 0;
};

class IntervalStats {
 public:
  static constexpr size_t kLatencySamples = 4096;  // per interval; more frames are not sampled

  IntervalStats(int interval_ms, const PipelineTally& tally, ipc::PoseRingWriter& ring);

  void add(const FrameTimes& t);
  // Ends the interval when it is over at `now_ns`: publishes and starts the next.
  void maybe_publish(int64_t now_ns);
  [[nodiscard]] ipc::RingStats last() const;

 private:
  int64_t interval_ns_;
  const PipelineTally& tally_;
  ipc::PoseRingWriter& ring_;
  std::vector<float> latencies_ms_;
  double sum_grab_ms_ = 0, sum_preprocess_ms_ = 0, sum_optimize_ms_ = 0, sum_publish_ms_ = 0;
  uint64_t frames_ = 0;
  int64_t start_ns_ = 0;
  mutable std::mutex last_mutex_;
  ipc::RingStats last_{};
};

}  // namespace handtrack::daemon
