#include "interval_stats.hpp"

#include "logging.hpp"

#include <algorithm>

namespace handtrack::daemon {

namespace {

// The q-quantile of `v` (reorders it).
float percentile(std::vector<float>& v, double q) {
  if (v.empty()) return 0.0F;
  const auto k =
      static_cast<size_t>(std::min<double>(static_cast<double>(v.size() - 1), q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace

IntervalStats::IntervalStats(int interval_ms, const PipelineTally& tally, ipc::PoseRingWriter& ring)
    : interval_ns_(static_cast<int64_t>(interval_ms) * 1'000'000), tally_(tally), ring_(ring) {
  latencies_ms_.reserve(kLatencySamples);
}

void IntervalStats::add(const FrameTimes& t) {
  sum_grab_ms_ += t.grab_ms;
  sum_preprocess_ms_ += t.preprocess_ms;
  sum_optimize_ms_ += t.optimize_ms;
  sum_publish_ms_ += t.publish_ms;
  ++frames_;
  if (latencies_ms_.size() < latencies_ms_.capacity()) latencies_ms_.push_back(t.latency_ms);
}

void IntervalStats::maybe_publish(int64_t now_ns) {
  if (start_ns_ == 0) start_ns_ = now_ns;
  const int64_t elapsed = now_ns - start_ns_;
  if (elapsed < interval_ns_) return;
  ipc::RingStats s{};
  const double n = static_cast<double>(std::max<uint64_t>(frames_, 1));
  s.fps = static_cast<float>(static_cast<double>(frames_) * 1e9 / static_cast<double>(elapsed));
  s.grab_ms = static_cast<float>(sum_grab_ms_ / n);
  s.preprocess_ms = static_cast<float>(sum_preprocess_ms_ / n);
  s.optimize_ms = static_cast<float>(sum_optimize_ms_ / n);
  s.publish_ms = static_cast<float>(sum_publish_ms_ / n);
  s.latency_p50_ms = percentile(latencies_ms_, 0.5);
  s.latency_p99_ms = percentile(latencies_ms_, 0.99);
  s.frames_captured = tally_.captured.load(std::memory_order_relaxed);
  s.frames_dropped = tally_.dropped.load(std::memory_order_relaxed);
  s.frames_skipped = tally_.skipped.load(std::memory_order_relaxed);
  s.source_errors = tally_.source_errors.load(std::memory_order_relaxed);
  ring_.set_stats(s);
  {
    std::lock_guard lock(last_mutex_);
    last_ = s;
  }
  log().debug(
      "{:.1f} fps; grab {:.1f} ms, preprocess {:.1f} ms, optimize {:.1f} ms, publish {:.2f} ms; latency p50 {:.1f} "
      "ms, p99 {:.1f} ms; {} captured, {} dropped, {} skipped, {} empty, {} source errors",
      s.fps, s.grab_ms, s.preprocess_ms, s.optimize_ms, s.publish_ms, s.latency_p50_ms, s.latency_p99_ms,
      s.frames_captured, s.frames_dropped, s.frames_skipped, tally_.empty_frames.load(std::memory_order_relaxed),
      s.source_errors);
  latencies_ms_.clear();
  sum_grab_ms_ = sum_preprocess_ms_ = sum_optimize_ms_ = sum_publish_ms_ = 0;
  frames_ = 0;
  start_ns_ = now_ns;
}

ipc::RingStats IntervalStats::last() const {
  std::lock_guard lock(last_mutex_);
  return last_;
}

}  // namespace handtrack::daemon
