#pragma once
// What every OpenNI2 source shares (the live camera here, the .oni recording in ../oni): error
// texts with OpenNI2's extended error, the depth unit of a pixel format, intrinsics from a depth
// stream, and OpenNi2SourceBase: one device, its depth stream and the copy of a frame.
//
// Thread roles: thread-bound: each source is driven by one thread (the pipeline's grab thread).
// OpenNI2's device events arrive on other threads and reach a source only through its DeviceWatch
// (atomics, openni2_runtime.hpp).
#include "handtrack/daemon/depth_source.hpp"

#include "logging.hpp"
#include "openni2_runtime.hpp"

#include "handtrack/common/clock.hpp"

#include <OpenNI.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

namespace handtrack::daemon::openni2 {

// waitForAnyStream is called in slices this long so that a device lost during a long grab
// timeout is reported within one slice rather than at the end of the timeout.
inline constexpr std::chrono::milliseconds kWaitSlice{50};

// OpenNI2's extended error of the last call, trimmed to one line (empty: none).
std::string extended_error();
// `what` with the extended error appended in parentheses, when there is one.
std::string with_detail(std::string what);
// Raw unit of a depth pixel format in mm; 0 for formats that are not depth.
double depth_unit_mm(openni::PixelFormat format);
// Pinhole intrinsics from the stream's field of view: a sensor w pixels wide seeing hfov radians
// has f_x = (w / 2) / tan(hfov / 2), likewise f_y from vfov; OpenNI2 reports no principal point,
// so it is the image centre (as in OpenNI2's own depth-to-world conversion).
bool intrinsics_from_stream(openni::VideoStream& stream, CameraIntrinsics* camera, std::string* why);

// The parts every OpenNI2 source shares: one device, its depth stream, frame copying.
class OpenNi2SourceBase : public DepthSource {
 public:
  // Opens through the subclass's open_impl(); on failure closes what was opened and prefixes the
  // reason with the source's name.
  bool open(std::string* why) override {
    std::string reason;
    const bool ok = open_impl(&reason);
    if (!ok) {
      close();
      if (why) *why = describe() + ": " + reason;
    }
    return ok;
  }
  [[nodiscard]] CameraIntrinsics camera() const override { return camera_; }
  [[nodiscard]] std::string last_error() const override { return last_error_; }

  void close() override {
    if (stream_) {
      stream_->stop();
      stream_->destroy();
      stream_.reset();
    }
    if (device_) {
      // A closed (or disconnected) openni::Device is never reused: the next open() makes a new one.
      device_->close();
      device_.reset();
    }
  }

 protected:
  ~OpenNi2SourceBase() override = default;

  // The device was opened into device_: creates and configures the depth stream (configure()
  // picks the mode), starts it and derives the intrinsics.
  bool open_depth_stream(std::string* why) {
    if (!device_->hasSensor(openni::SENSOR_DEPTH)) {
      *why = "the device has no depth sensor";
      return false;
    }
    stream_ = std::make_unique<openni::VideoStream>();
    if (stream_->create(*device_, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
      *why = with_detail("cannot create the depth stream");
      stream_.reset();
      return false;
    }
    if (!configure(why)) return false;
    if (stream_->start() != openni::STATUS_OK) {
      *why = with_detail("cannot start the depth stream");
      return false;
    }
    return intrinsics_from_stream(*stream_, &camera_, why);
  }

  virtual bool open_impl(std::string* why) = 0;
  virtual bool configure(std::string* why) = 0;

  enum class Wait { kReady, kTimeout, kLost, kError };

  // Waits for the depth stream without ever blocking in readFrame (it can block for ever once a
  // device is gone): waitForAnyStream with a timeout, and only then readFrame.
  Wait wait_ready(std::chrono::milliseconds timeout, const std::atomic<bool>* lost) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    openni::VideoStream* streams[] = {stream_.get()};
    for (;;) {
      if (lost && lost->load(std::memory_order_acquire)) return Wait::kLost;
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      const auto slice = std::clamp(left, std::chrono::milliseconds(0), kWaitSlice);
      int ready = -1;
      const openni::Status rc = openni::OpenNI::waitForAnyStream(streams, 1, &ready, static_cast<int>(slice.count()));
      if (rc == openni::STATUS_OK && ready == 0) return Wait::kReady;
      if (rc != openni::STATUS_OK && rc != openni::STATUS_TIME_OUT) return Wait::kError;
      if (left <= std::chrono::milliseconds(0)) return Wait::kTimeout;
    }
  }

  // Reads the ready frame into `frame` (in place: depth_raw keeps its buffer once sized).
  GrabStatus read_ready_frame(RawFrame& frame, int* frame_index) {
    openni::VideoFrameRef ref;
    if (stream_->readFrame(&ref) != openni::STATUS_OK || !ref.isValid()) return bad_frame("readFrame failed");
    const int w = ref.getWidth();
    const int h = ref.getHeight();
    if (w != camera_.width || h != camera_.height) {
      return bad_frame("frame of " + std::to_string(w) + "x" + std::to_string(h) + " in a " +
                       std::to_string(camera_.width) + "x" + std::to_string(camera_.height) + " stream");
    }
    if (depth_unit_mm(ref.getVideoMode().getPixelFormat()) != camera_.depth_scale_mm) {
      return bad_frame("frame with a different depth pixel format");
    }
    const auto row_bytes = static_cast<size_t>(w) * sizeof(uint16_t);
    const int stride = ref.getStrideInBytes() > 0 ? ref.getStrideInBytes() : static_cast<int>(row_bytes);
    if (static_cast<size_t>(stride) < row_bytes ||
        static_cast<int64_t>(ref.getDataSize()) < static_cast<int64_t>(stride) * (h - 1) + static_cast<int64_t>(row_bytes)) {
      return bad_frame("frame data smaller than its size says");
    }
    frame.depth_raw.resize(static_cast<size_t>(w) * static_cast<size_t>(h));
    const auto* src = static_cast<const uint8_t*>(ref.getData());
    for (int v = 0; v < h; ++v) {
      std::memcpy(frame.depth_raw.data() + static_cast<size_t>(v) * static_cast<size_t>(w),
                  src + static_cast<size_t>(v) * static_cast<size_t>(stride), row_bytes);
    }
    frame.camera = camera_;
    frame.frame_number = static_cast<uint64_t>(std::max(0, ref.getFrameIndex()));
    frame.capture_ns = monotonic_ns();
    *frame_index = ref.getFrameIndex();
    return GrabStatus::kFrame;
  }

  // A bad frame: skipped and counted by the pipeline, which logs last_error() rate-limited.
  GrabStatus bad_frame(std::string what) {
    last_error_ = std::move(what);
    return GrabStatus::kError;
  }

  std::shared_ptr<Runtime> runtime_;
  std::unique_ptr<openni::Device> device_;
  std::unique_ptr<openni::VideoStream> stream_;
  CameraIntrinsics camera_;
  std::string last_error_;
};
}  // namespace handtrack::daemon::openni2
