#pragma once
// OptimizeStage: the pose for one frame's C_I (paper Sec. 4-5: particles, gradient ascent, late
// fusion when the frame carries part labels; the choice of hand), and the request that guides the
// next frames' preprocessing (which hands, and the hints for their segmentation). A frame with no hand, or the first of a new resolution, restarts the tracker.
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
  OptimizeStage(const TrackerConfig& config, TrackerReload& reload, RequestMailbox& request, StageWatch& watch);

  void step(Frame& frame);

 private:
  void apply_reload();

  TrackerReload& reload_;
  RequestMailbox& request_;
  StageWatch& watch_;
  std::optional<Tracker> tracker_;
  uint64_t tracker_generation_ = 0;
};

}  // namespace handtrack::daemon
