#pragma once
// OptimizeStage: the poses of one frame's hands (paper Sec. 4-5 per hand: particles, gradient
// ascent, late fusion when the frame carries part labels; the choice of left or right hand; the
// hands' slots and ids: HandsTracker), and the request that guides the next frames'
// preprocessing (which hands, their segmentation hints, their last poses). With two hands in a
// frame the second is optimized on a side thread while the optimize thread does the first, so the
// two hands take about as long as one (issue 14; the paper's Sec. 7 runs stages on separate cores
// the same way). The poses, fitted in the image turned upright for a camera mounted turned
// (camera.roll), go out in the camera's own frame. A frame with no depth, or the first of a new
// resolution, restarts the tracker. A reloaded configuration (SIGHUP) rebuilds the tracker between
// two frames.
//
// Thread roles: thread-bound: step() from the optimize thread (or the single thread); the side
// thread runs only HandsTracker::fit() of the second hand, between post() and wait() in step().
#include "frame.hpp"
#include "stage_links.hpp"
#include "stage_watch.hpp"

#include "handtrack/common/side_thread.hpp"
#include "handtrack/core/camera_roll.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

namespace handtrack::daemon {

class OptimizeStage {
 public:
  // `side`: optimize a frame's second hand on a side thread (not in --single-thread mode, whose
  // point is one thread); `side_setup` runs first on that thread (name, CPU). `roll`: how the
  // camera is mounted (PreprocessStage turned its frames upright).
  OptimizeStage(const TrackerConfig& config, CameraRoll roll, TrackerReload& reload, RequestMailbox& request,
                StageWatch& watch, bool side, std::function<void()> side_setup = {});

  void step(Frame& frame);

 private:
  void apply_reload();

  TrackerReload& reload_;
  RequestMailbox& request_;
  StageWatch& watch_;
  CameraRoll roll_;
  std::optional<HandsTracker> tracker_;
  uint64_t tracker_generation_ = 0;
  // The side thread's job: fit slot 1 of the frame being optimized (set before post()).
  const HandsInputs* side_inputs_ = nullptr;
  std::function<void()> fit_side_;
  std::unique_ptr<SideThread> side_;
};

}  // namespace handtrack::daemon
