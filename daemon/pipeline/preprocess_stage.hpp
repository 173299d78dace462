#pragma once
// PreprocessStage: raw depth -> C_I (paper Sec. 3.1, 4.3): depth to mm, the working-volume test,
// the image turned upright for a camera mounted turned (camera.roll, camera_roll.hpp), then the
// frame's HandsInputs for the hands the tracker asked for (the frame shared out among the hands,
// median filter, segmentation guided by each last pose's hint, quadtree Gaussians, part labels
// when a forest is loaded). Frames whose buffer does not match their intrinsics are marked
// malformed (skipped and counted at publish); frames with no depth in the working volume are marked
// empty (published as no_hand). The first frame of a new resolution is marked so that the
// optimizer restarts.
//
// With two hands in a frame the second hand's input is built on a side thread while the preprocess
// thread builds the first's (the forest's labels are most of the work; PartForest is thread-safe).
//
// Thread roles: thread-bound: step() from the preprocess thread (or the single thread); the side
// thread runs only HandsInputs::build_slot() of the second hand, between post() and wait() in step().
#include "frame.hpp"
#include "pipeline_tally.hpp"
#include "stage_links.hpp"
#include "stage_watch.hpp"

#include "handtrack/common/side_thread.hpp"
#include "handtrack/core/camera_roll.hpp"
#include "handtrack/core/part_forest.hpp"

#include <functional>
#include <memory>

namespace handtrack::daemon {

class PreprocessStage {
 public:
  // `forest` may be null (depth-only); it outlives the stage.
  // `side`: build a frame's second hand on a side thread (not in --single-thread mode);
  // `side_setup` runs first on that thread (name, CPU).
  // `roll`: how the camera is mounted; the frames' depth is turned upright.
  PreprocessStage(const TrackerConfig& config, CameraRoll roll, TrackerReload& reload, const RequestMailbox& request,
                  const PartForest* forest, PipelineTally& tally, StageWatch& watch, bool side = false,
                  std::function<void()> side_setup = {});

  // Inputs for a new pool frame, for the configuration in force. They borrow the stage's splitter
  // (they are shared out one at a time, in step()), so the stage must outlive them.
  [[nodiscard]] HandsInputs make_inputs() { return HandsInputs(input_config_, splitter_); }
  void step(Frame& frame);

 private:
  void apply_reload();

  TrackerReload& reload_;
  const RequestMailbox& request_;
  const PartForest* forest_;
  PipelineTally& tally_;
  StageWatch& watch_;
  DepthInputConfig input_config_;
  CameraRoll roll_;
  DepthImage camera_depth_;  // a turned camera's frame in mm, before it is turned upright
  FrameSplitter splitter_;  // every pool frame's: only step() shares a frame out
  uint64_t input_generation_ = 0;
  int stream_width_ = 0;
  int stream_height_ = 0;
  // The side thread's job: slot 1 of the frame being preprocessed (set before post()).
  Frame* side_frame_ = nullptr;
  HandsRequest side_request_;
  std::function<void()> build_side_;
  std::unique_ptr<SideThread> side_;
};

}  // namespace handtrack::daemon
