#pragma once
// handtrackd's pipeline: grab -> preprocess -> optimize -> publish, one thread each, joined by
// bounded lock-free single-producer/single-consumer queues (Boost.Lockfree), so that frame t+1 is
// preprocessed while frame t is optimized (issue 5; the paper's Sec. 7 runs the stages on separate
// cores the same way).
//
//   grab ──raw──> preprocess ──input──> optimize ──result──> publish ──> PoseRingWriter
//     ^              │ (drop)              │ (drop)             │
//     └──── free ────┴─────────────────────┴────────────────────┘   (one SPSC queue per returner)
//
// Frames come from a pool allocated at start(); a frame's buffers are sized by the first frame of
// a resolution and then reused, so the steady state allocates nothing (tests/daemon counts it).
// Live sources and paced recordings: when the optimizer falls behind, the newest frame wins
// (preprocess and optimize each take the newest queued frame and drop the older ones, counted).
// Recordings and the virtual camera with `fast`: nothing is dropped, every frame is tracked as
// fast as the stages allow (back-pressure instead of drops).
//
// Thread roles: start(), stop(), reload() and the const observers are called from one control
// thread (handtrackd's main thread); everything else runs on the pipeline's own threads.

#include "handtrack/daemon/config.hpp"
#include "handtrack/daemon/depth_source.hpp"
#include "handtrack/ipc/pose_ring_writer.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace handtrack::daemon {

// Counters since start (monotonic) and the latest statistics interval.
struct PipelineCounters {
  uint64_t frames_captured = 0;     // frames the source delivered
  uint64_t frames_published = 0;    // poses written to the ring
  uint64_t frames_dropped = 0;      // captured, never tracked (the optimizer was behind)
  uint64_t frames_skipped = 0;      // captured, not tracked: malformed (size does not match the intrinsics)
  uint64_t frames_empty = 0;        // no depth in the working volume (all zero or all far): published as no_hand
  uint64_t source_errors = 0;       // GrabStatus::kError (bad frames skipped by the source)
  uint64_t resolution_changes = 0;  // the stream's resolution changed (buffers rebuilt)
  uint64_t records_dropped = 0;     // --record: frames not written because the recorder was behind
  uint64_t frames_recorded = 0;
  ipc::RingStats last_stats{};      // what went into the ring header last
  int64_t first_capture_ns = 0;     // CLOCK_MONOTONIC of the first frame (throughput = published / span)
  int64_t last_publish_ns = 0;
  int32_t tracking_state = 0;       // of the last published pose (handtrack_tracking_state)
  ipc::DeviceState device_state = ipc::DeviceState::kStarting;
};

enum class Health {
  kProgressing,     // frames flow, or a stage is legitimately idle (waiting for frames or a device)
  kStalled,         // a stage has been busy on one frame for longer than stall_timeout_ms
};

class Pipeline {
 public:
  // The source must already be constructed; the pipeline opens it (and for live sources keeps
  // retrying). `ring` outlives the pipeline.
  Pipeline(const DaemonConfig& config, std::unique_ptr<DepthSource> source, ipc::PoseRingWriter& ring);
  ~Pipeline();  // stop() and join
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Opens a recording source synchronously (false with *why on failure: a missing or corrupt
  // sequence is an error at start, not something to wait for); a live source is opened by the
  // grab thread, which waits for the device. Then allocates the pool and starts the threads.
  bool start(std::string* why);
  // Asks every stage to stop; returns at once. The destructor joins.
  void stop();
  void join();
  // The source ended (recording without loop, or config.max_frames reached) and every grabbed
  // frame was published or dropped; or a stage failed (see failed()).
  [[nodiscard]] bool finished() const;
  [[nodiscard]] bool failed() const;

  [[nodiscard]] Health health() const;
  // Which stage is stalled and for how long (for the log), when health() is kStalled.
  [[nodiscard]] std::string stall_description() const;
  [[nodiscard]] PipelineCounters counters() const;

  // SIGHUP: new tracker parameters, applied between two frames (the tracker restarts from the
  // open hand; buffers are kept).
  void reload(const TrackerConfig& tracker);

  [[nodiscard]] const DepthSource& source() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace handtrack::daemon
