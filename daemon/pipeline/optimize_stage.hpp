#pragma once
// OptimizeStage: the pose for one frame's C_I (paper Sec. 4-5: particles, gradient ascent, late
// fusion when the frame carries part labels), and the hint that guides the next frames'
// segmentation. A frame with no hand, or the first of a new resolution, restarts the tracker.
// A reloaded configuration (SIGHUP) rebuilds the tracker between two frames.
//
// Thread roles: thread-bound: step() from the optimize thread (or the single thread).
#include "frame.hpp"
#include "stage_links.hpp"
#include "stage_watch.hpp"

#include <cstdint>
#include <optional>

namespace handtrack::daemon {

class OptimizeStage {
 public:
  OptimizeStage(const TrackerConfig& config, TrackerReload& reload, HintMailbox& hint, StageWatch& watch);

  void step(Frame& frame);

 private:
  void apply_reload();

  TrackerReload& reload_;
  HintMailbox& hint_;
  StageWatch& watch_;
  std::optional<PoseTracker> tracker_;
  uint64_t tracker_generation_ = 0;
};

}  // namespace handtrack::daemon
