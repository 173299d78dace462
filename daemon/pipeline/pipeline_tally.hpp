#pragma once
// PipelineTally: the pipeline's counters, written by the stages, read by the control thread
// (Pipeline::counters(), finished()).
//
// Thread roles: thread-safe; each counter has one writing stage (noted), any thread reads.
//
// SYNC: plain counters are relaxed: they are statistics, read for logs and STATUS=, and carry no
// other data. The exceptions are `captured` and `completed`, which decide Pipeline::finished():
// their increments are acq_rel and finished() loads them with acquire after the grab thread's
// release store of `grab_done` (pipeline.cpp), so a finished() that returns true has seen every
// capture, and every stage's work on every frame happened before it.
#include "handtrack/daemon/pipeline.hpp"

#include <atomic>
#include <cstdint>

namespace handtrack::daemon {

struct PipelineTally {
  std::atomic<uint64_t> captured{0};            // grab
  std::atomic<uint64_t> completed{0};           // published + dropped + skipped; any stage
  std::atomic<uint64_t> published{0};           // publish
  std::atomic<uint64_t> dropped{0};             // preprocess, optimize, grab
  std::atomic<uint64_t> skipped{0};             // publish
  std::atomic<uint64_t> empty_frames{0};        // publish
  std::atomic<uint64_t> source_errors{0};       // grab
  std::atomic<uint64_t> resolution_changes{0};  // preprocess
  std::atomic<uint64_t> records_dropped{0};     // grab (recorder full), recorder
  std::atomic<uint64_t> frames_recorded{0};     // recorder
  std::atomic<int64_t> first_capture_ns{0};     // grab
  std::atomic<int64_t> last_publish_ns{0};      // publish
  std::atomic<int32_t> tracking_state{0};       // publish (handtrack_tracking_state)
  std::atomic<uint32_t> device_state{static_cast<uint32_t>(ipc::DeviceState::kStarting)};  // grab, start()

  // `n` frames left the pipeline without being published.
  void count_drop(uint64_t n) {
    dropped.fetch_add(n, std::memory_order_relaxed);
    complete(n);
  }
  // SYNC: acq_rel, see the top of this file.
  void complete(uint64_t n = 1) { completed.fetch_add(n, std::memory_order_acq_rel); }

  // Everything but last_stats (kept by IntervalStats).
  [[nodiscard]] PipelineCounters snapshot() const {
    PipelineCounters c;
    c.frames_captured = captured.load(std::memory_order_relaxed);
    c.frames_published = published.load(std::memory_order_relaxed);
    c.frames_dropped = dropped.load(std::memory_order_relaxed);
    c.frames_skipped = skipped.load(std::memory_order_relaxed);
    c.frames_empty = empty_frames.load(std::memory_order_relaxed);
    c.source_errors = source_errors.load(std::memory_order_relaxed);
    c.resolution_changes = resolution_changes.load(std::memory_order_relaxed);
    c.records_dropped = records_dropped.load(std::memory_order_relaxed);
    c.frames_recorded = frames_recorded.load(std::memory_order_relaxed);
    c.first_capture_ns = first_capture_ns.load(std::memory_order_relaxed);
    c.last_publish_ns = last_publish_ns.load(std::memory_order_relaxed);
    c.tracking_state = tracking_state.load(std::memory_order_relaxed);
    c.device_state = static_cast<ipc::DeviceState>(device_state.load(std::memory_order_relaxed));
    return c;
  }
};

}  // namespace handtrack::daemon
