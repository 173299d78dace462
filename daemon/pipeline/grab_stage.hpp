#pragma once
// GrabStage: the first stage. Opens the source (a live camera: retried once a second until it
// appears, and again after it went away), grabs one frame at a time into a pool Frame, stamps it
// with the daemon's frame number and capture time, and offers it to the recorder. The device
// state it reports goes into the ring header.
//
// Thread roles: start() from the control thread before the pipeline threads exist; step() from
// the grab thread (or the single thread); close() from the control thread after they joined.
#include "doorbell.hpp"
#include "frame.hpp"
#include "pipeline_tally.hpp"
#include "stage_watch.hpp"
#include "throttle.hpp"

#include "handtrack/daemon/config.hpp"
#include "handtrack/ipc/pose_ring_writer.hpp"

#include <cstdint>
#include <string>

namespace handtrack::daemon {

class Recorder;

class GrabStage {
 public:
  enum class Step {
    kFrame,    // `frame` holds a new frame
    kNothing,  // no frame this time (waiting for the device, a timeout, a bad frame skipped)
    kDone,     // the source ended, or max_frames were grabbed
  };

  GrabStage(const DaemonConfig& config, DepthSource& source, ipc::PoseRingWriter& ring, PipelineTally& tally,
            StageWatch& watch, Doorbell& bell, Recorder* recorder);

  // A recording or the virtual camera is opened here, synchronously: a missing or corrupt file is
  // an error at start, not something to wait for (false with *why). A live source is opened by
  // step(), which waits for the device.
  bool start(std::string* why);
  Step step(Frame& frame);
  void close();

 private:
  bool open_source();
  void set_device_state(ipc::DeviceState state);

  const DaemonConfig& config_;
  DepthSource& source_;
  ipc::PoseRingWriter& ring_;
  PipelineTally& tally_;
  StageWatch& watch_;
  Doorbell& bell_;  // rung when a frame comes free; wakes a grab thread waiting to reopen
  Recorder* recorder_;
  bool open_ = false;
  bool failed_ = false;  // a recording's source failed (GrabStatus::kFailed): no more frames
  uint64_t next_seq_ = 0;
  int64_t next_open_ns_ = 0;
  std::string last_open_problem_;
  Throttle error_log_;
};

}  // namespace handtrack::daemon
