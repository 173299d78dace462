#pragma once
// PreprocessStage: raw depth -> C_I (paper Sec. 3.1, 4.3): depth to mm, the working-volume test,
// then the frame's HandsInputs for the hands the tracker asked for (the frame shared out among
// the hands, median filter, segmentation guided by each last pose's hint, quadtree Gaussians, part labels when a forest is loaded). Frames whose buffer does not match
// their intrinsics are marked malformed (skipped and counted at publish); frames with no depth in
// the working volume are marked empty (published as no_hand). The first frame of a new resolution
// is marked so that the optimizer restarts.
//
// Thread roles: thread-bound: step() from the preprocess thread (or the single thread).
#include "frame.hpp"
#include "pipeline_tally.hpp"
#include "stage_links.hpp"
#include "stage_watch.hpp"

#include "handtrack/core/part_forest.hpp"

namespace handtrack::daemon {

class PreprocessStage {
 public:
  // `forest` may be null (depth-only); it outlives the stage.
  PreprocessStage(const TrackerConfig& config, TrackerReload& reload, const RequestMailbox& request,
                  const PartForest* forest, PipelineTally& tally, StageWatch& watch);

  // Inputs for a new pool frame, for the configuration in force.
  [[nodiscard]] HandsInputs make_inputs() const { return HandsInputs(input_config_); }
  void step(Frame& frame);

 private:
  void apply_reload();

  TrackerReload& reload_;
  const RequestMailbox& request_;
  const PartForest* forest_;
  PipelineTally& tally_;
  StageWatch& watch_;
  DepthInputConfig input_config_;
  uint64_t input_generation_ = 0;
  int stream_width_ = 0;
  int stream_height_ = 0;
};

}  // namespace handtrack::daemon
