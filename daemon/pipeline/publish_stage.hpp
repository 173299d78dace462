#pragma once
// PublishStage: the last stage. Writes one frame into the ring (its record: the frame's hands,
// stamped with its stage timings; no hand seen: hand_count 0), counts skipped and empty frames, feeds the interval
// statistics, and logs tracking-state changes at most once a second.
//
// Thread roles: thread-bound: step() from the publish thread (or the single thread).
#include "frame.hpp"
#include "interval_stats.hpp"
#include "pipeline_tally.hpp"
#include "stage_watch.hpp"

#include "handtrack/ipc/pose_ring_writer.hpp"

#include <cstdint>

namespace handtrack::daemon {

class PublishStage {
 public:
  PublishStage(ipc::PoseRingWriter& ring, PipelineTally& tally, StageWatch& watch, IntervalStats& stats);

  void step(const Frame& frame);

 private:
  void log_state_change(TrackingState state, int64_t now_ns);

  ipc::PoseRingWriter& ring_;
  PipelineTally& tally_;
  StageWatch& watch_;
  IntervalStats& stats_;
  ipc::FrameRecord record_{};  // every field is set per frame (fill_hands clears the hands)
  int32_t logged_state_ = -1;
  uint64_t state_changes_ = 0;
  int64_t state_logged_ns_ = 0;
};

}  // namespace handtrack::daemon
