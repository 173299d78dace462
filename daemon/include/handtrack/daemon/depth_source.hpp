#pragma once
// Where handtrackd's depth frames come from: one interface in front of every camera, recording
// and virtual camera (like libcamera's PipelineHandler). SPEC.md "Sources":
//   openni2 | openni2:URI | oni:FILE.oni | seq:DIR | synthetic[:MOTION]
// The OpenNI2 sources run in a helper process (handtrack-source-helper): a driver fault ends
// the helper, not the daemon.
//
// Thread roles: a DepthSource is driven by one thread, the pipeline's grab thread.
// Error policy: open() reports why it failed in its return value; grab() returns a status and
// never throws. Construction (make_source) may throw with a message naming the source.

#include "handtrack/core/camera.hpp"

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace handtrack::daemon {

// One depth frame in the sensor's raw units (value * camera.depth_scale_mm = mm, 0 = none).
// The pipeline owns a pool of these, allocated at start: grab() fills one in place and must not
// reallocate `depth_raw` once it has the source's size.
struct RawFrame {
  CameraIntrinsics camera;
  std::vector<uint16_t> depth_raw;
  uint64_t frame_number = 0;  // the source's own index (recording: frame in the file)
  int64_t capture_ns = 0;     // CLOCK_MONOTONIC when the frame was taken or read
};

enum class GrabStatus {
  kFrame,         // `frame` holds a new frame
  kTimeout,       // nothing within the timeout (a live camera may be slow or just unplugged)
  kEndOfStream,   // a recording played to its end (and does not loop)
  kDisconnected,  // the device went away: close() and open() again later
  kError,         // a bad frame or read error: skipped and counted; streaming continues
  kFailed,        // the source cannot go on (its driver process died or hung): state "error";
                  // a live camera is reopened later, a recording stays failed
};

struct SourceOptions {
  bool loop = false;               // recordings: start again at the end
  bool as_fast_as_possible = false;  // recordings: no pacing at their own frame rate (--fast)
  // openni2: preferred depth mode (Sec. 7 used 320x240 at 60 fps); falls back to 640x480@30.
  // synthetic: its frame rate (the motions keep their speed in seconds).
  int width = 320;
  int height = 240;
  int fps = 60;
  // synthetic: frames in one pass of the motion and the random seed of subject and noise.
  int synthetic_frames = 600;
  uint64_t seed = 1;
  // synthetic: render one period of frames into memory when the source is made and play them
  // from there, so that a frame costs the host no CPU, as a camera's does (latency benchmarks:
  // ray casting takes 1-2 ms a frame, a quarter to half of a core at 250 fps on 2 cores).
  bool synthetic_prerender = false;
};

class DepthSource {
 public:
  virtual ~DepthSource() = default;
  DepthSource() = default;
  DepthSource(const DepthSource&) = delete;
  DepthSource& operator=(const DepthSource&) = delete;

  // Human-readable name for logs, e.g. "oni:/data/x.oni".
  [[nodiscard]] virtual std::string describe() const = 0;
  // Opens (or reopens after kDisconnected) the device. False with *why set when it is not
  // available (no camera plugged in yet, unreadable file); the pipeline retries live devices.
  virtual bool open(std::string* why) = 0;
  virtual void close() = 0;
  // Waits at most `timeout` for the next frame. Must return within about the timeout even when a
  // device vanished (OpenNI2's readFrame can block for ever after an unplug: never call it
  // without a ready stream).
  virtual GrabStatus grab(RawFrame& frame, std::chrono::milliseconds timeout) = 0;
  // Intrinsics of the frames grab() delivers; valid after a successful open().
  [[nodiscard]] virtual CameraIntrinsics camera() const = 0;
  // True for cameras (retry open and reopen on loss), false for recordings and the virtual camera.
  [[nodiscard]] virtual bool is_live() const = 0;
  // Why the last grab() returned kError, kDisconnected or kFailed, for the log (empty: no details).
  // Added for the pipeline's "skipped and counted" log line; a default so sources may ignore it.
  [[nodiscard]] virtual std::string last_error() const { return {}; }
};

// Parses SRC (SPEC.md "Sources") and builds the source. Throws std::invalid_argument naming SRC
// when it is malformed (unknown scheme, unknown motion, missing path).
std::unique_ptr<DepthSource> make_source(const std::string& spec, const SourceOptions& options);

}  // namespace handtrack::daemon
