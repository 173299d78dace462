// OpenNI2 sources: a live camera (first device or a URI, reopened after unplug) and an .oni
// recording played through OpenNI2's own OniFile driver. See docs/OPENNI2.md.
//
// @thread Each source is driven by one thread (the pipeline's grab thread). OpenNI2's device
// events arrive on other threads and reach a source only through its DeviceWatch (atomics).
#include "handtrack/daemon/openni2_source.hpp"

#include "openni2_runtime.hpp"

#include <OpenNI.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace handtrack::daemon {

namespace {

using openni2::DeviceWatch;
using openni2::Runtime;

// waitForAnyStream is called in slices this long so that a device lost during a long grab
// timeout is reported within one slice rather than at the end of the timeout.
constexpr std::chrono::milliseconds kWaitSlice{50};
// Fallback mode when the requested one is not offered (PrimeSense/Kinect-class sensors' default).
constexpr int kFallbackWidth = 640;
constexpr int kFallbackHeight = 480;
constexpr int kFallbackFps = 30;
// A live camera without frames this long is closed and reopened (see stalled_device_gone).
constexpr int64_t kStallReopenNs = 3'000'000'000;
// A recording whose length OpenNI2 does not report has ended when no frame came for this long.
constexpr int64_t kRecordingSilenceNs = 3'000'000'000;

std::shared_ptr<spdlog::logger> logger() {
  auto log = spdlog::get("daemon");
  return log ? log : spdlog::default_logger();
}

std::string extended_error() {
  const char* e = openni::OpenNI::getExtendedError();
  std::string s = e ? e : "";
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  s = s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s;
}

std::string with_detail(std::string what) {
  const std::string detail = extended_error();
  if (!detail.empty()) what += " (" + detail + ")";
  return what;
}

// Raw unit of a depth pixel format in mm; 0 for formats that are not depth.
double depth_unit_mm(openni::PixelFormat format) {
  switch (format) {
    case openni::PIXEL_FORMAT_DEPTH_1_MM:
      return 1.0;
    case openni::PIXEL_FORMAT_DEPTH_100_UM:
      return 0.1;
    default:
      return 0.0;
  }
}

// Pinhole intrinsics from the stream's field of view: a sensor w pixels wide seeing hfov radians
// has f_x = (w / 2) / tan(hfov / 2), likewise f_y from vfov; OpenNI2 reports no principal point,
// so it is the image centre (as in OpenNI2's own depth-to-world conversion).
bool intrinsics_from_stream(openni::VideoStream& stream, CameraIntrinsics* camera, std::string* why) {
  const openni::VideoMode mode = stream.getVideoMode();
  const double unit_mm = depth_unit_mm(mode.getPixelFormat());
  if (unit_mm == 0.0) {
    *why = "the depth stream delivers pixel format " + std::to_string(static_cast<int>(mode.getPixelFormat())) +
           ", not depth in 1 mm or 100 um";
    return false;
  }
  const double hfov = stream.getHorizontalFieldOfView();
  const double vfov = stream.getVerticalFieldOfView();
  if (!(hfov > 0.0 && hfov < M_PI) || !(vfov > 0.0 && vfov < M_PI)) {
    *why = "the depth stream reports no usable field of view (h " + std::to_string(hfov) + ", v " +
           std::to_string(vfov) + " rad)";
    return false;
  }
  CameraIntrinsics c;
  c.width = mode.getResolutionX();
  c.height = mode.getResolutionY();
  c.fx = 0.5 * c.width / std::tan(0.5 * hfov);
  c.fy = 0.5 * c.height / std::tan(0.5 * vfov);
  c.cx = 0.5 * c.width;
  c.cy = 0.5 * c.height;
  c.depth_scale_mm = unit_mm;
  c.fps = mode.getFps() > 0 ? mode.getFps() : 30.0;
  if (const std::string problem = c.problem(); !problem.empty()) {
    *why = "intrinsics from the device are unusable: " + problem;
    return false;
  }
  *camera = c;
  return true;
}

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
    frame.capture_ns = openni2::monotonic_ns();
    *frame_index = ref.getFrameIndex();
    return GrabStatus::kFrame;
  }

  // A bad frame: skipped and counted by the pipeline, which logs last_error() rate-limited.
  GrabStatus bad_frame(std::string what) {
    ++bad_frames_;
    last_error_ = std::move(what);
    return GrabStatus::kError;
  }

  std::shared_ptr<Runtime> runtime_;
  std::unique_ptr<openni::Device> device_;
  std::unique_ptr<openni::VideoStream> stream_;
  CameraIntrinsics camera_;
  uint64_t bad_frames_ = 0;
  std::string last_error_;
};

// ---------------------------------------------------------------------------------------------
// Live camera.

class OpenNi2Camera final : public OpenNi2SourceBase {
 public:
  OpenNi2Camera(std::string uri, const SourceOptions& options)
      : uri_(std::move(uri)), options_(options), watch_(std::make_shared<DeviceWatch>()) {}
  ~OpenNi2Camera() override { close(); }

  [[nodiscard]] std::string describe() const override { return uri_.empty() ? "openni2" : "openni2:" + uri_; }
  [[nodiscard]] bool is_live() const override { return true; }

  void close() override {
    OpenNi2SourceBase::close();
    std::lock_guard lock(watch_->uri_mutex);
    watch_->uri.clear();
  }

  GrabStatus grab(RawFrame& frame, std::chrono::milliseconds timeout) override {
    if (!stream_) {
      last_error_ = "not open";
      return GrabStatus::kDisconnected;
    }
    switch (wait_ready(timeout, &watch_->lost)) {
      case Wait::kReady: {
        int index = 0;
        const GrabStatus status = read_ready_frame(frame, &index);
        if (status == GrabStatus::kFrame) last_frame_ns_ = frame.capture_ns;
        return status;
      }
      case Wait::kTimeout:
        return stalled_device_gone() ? GrabStatus::kDisconnected : GrabStatus::kTimeout;
      case Wait::kLost:
        last_error_ = "OpenNI2 reported device " + open_uri_ + " disconnected";
        return GrabStatus::kDisconnected;
      case Wait::kError:
        break;
    }
    // waitForAnyStream failed outright: the stream or its device is unusable.
    last_error_ = with_detail("waiting for a frame failed");
    return GrabStatus::kDisconnected;
  }

 private:
  // A camera that stays silent for kStallReopenNs is treated as lost: OpenNI2 drops a device
  // from its list only when the driver raises the disconnect event, and a driver that misses it
  // (or a sensor that stalls while still attached) would otherwise leave grab() timing out for
  // ever. Reopening recovers both.
  bool stalled_device_gone() {
    const int64_t silent_ns = openni2::monotonic_ns() - last_frame_ns_;
    if (silent_ns < kStallReopenNs) return false;
    last_error_ = "no frame from " + open_uri_ + " for " + std::to_string(silent_ns / 1'000'000) + " ms";
    return true;
  }

  bool open_impl(std::string* why) override {
    close();
    if (!runtime_) {
      runtime_ = Runtime::acquire(why);
      if (!runtime_) return false;
      runtime_->add_watch(watch_);
    }
    const std::vector<std::string> uris = Runtime::device_uris();
    std::string chosen;
    if (uri_.empty()) {
      if (!uris.empty()) chosen = uris.front();
    } else if (std::find(uris.begin(), uris.end(), uri_) != uris.end()) {
      chosen = uri_;
    }
    if (chosen.empty()) {
      *why = uri_.empty() ? "waiting for a device: no OpenNI2 depth camera is connected"
                          : "waiting for a device: " + uri_ + " is not connected";
      return false;
    }
    {
      // Watch the URI before opening: a disconnect between here and the first grab is not lost.
      std::lock_guard lock(watch_->uri_mutex);
      watch_->uri = chosen;
      watch_->lost.store(false, std::memory_order_release);
    }
    device_ = std::make_unique<openni::Device>();
    if (device_->open(chosen.c_str()) != openni::STATUS_OK) {
      *why = with_detail("cannot open device " + chosen);
      return false;
    }
    if (!open_depth_stream(why)) {
      *why = chosen + ": " + *why;
      return false;
    }
    open_uri_ = chosen;
    last_frame_ns_ = openni2::monotonic_ns();
    logger()->info("{}: opened {} ({}x{} at {} fps, f {:.1f}/{:.1f} px, depth unit {} mm)", describe(), chosen,
                   camera_.width, camera_.height, camera_.fps, camera_.fx, camera_.fy, camera_.depth_scale_mm);
    return true;
  }

  // Mode: the requested one (Sec. 7 of the paper ran 320x240 at 60 fps) if the sensor offers it
  // in a depth format, else 640x480 at 30, else the sensor's current mode. Mirroring off: the
  // tracker works in the camera frame, x right as the sensor sees it.
  bool configure(std::string* why) override {
    const openni::SensorInfo& info = stream_->getSensorInfo();
    const openni::Array<openni::VideoMode>& modes = info.getSupportedVideoModes();
    auto find_mode = [&](int w, int h, int fps) -> const openni::VideoMode* {
      const openni::VideoMode* best = nullptr;
      for (int i = 0; i < modes.getSize(); ++i) {
        const openni::VideoMode& m = modes[i];
        if (m.getResolutionX() != w || m.getResolutionY() != h || m.getFps() != fps) continue;
        const double unit = depth_unit_mm(m.getPixelFormat());
        if (unit == 0.0) continue;
        if (!best || unit == 1.0) best = &m;  // prefer whole millimetres
      }
      return best;
    };
    const openni::VideoMode* mode = find_mode(options_.width, options_.height, options_.fps);
    if (!mode) mode = find_mode(kFallbackWidth, kFallbackHeight, kFallbackFps);
    const openni::VideoMode current = stream_->getVideoMode();
    const bool already = mode && current.getResolutionX() == mode->getResolutionX() &&
                         current.getResolutionY() == mode->getResolutionY() && current.getFps() == mode->getFps() &&
                         current.getPixelFormat() == mode->getPixelFormat();
    // Set only what differs: OpenNI2 refuses any change (even to the same mode) while another
    // stream on the same sensor runs.
    if (mode && !already) {
      if (stream_->setVideoMode(*mode) != openni::STATUS_OK) {
        *why = with_detail("cannot set depth mode " + std::to_string(mode->getResolutionX()) + "x" +
                           std::to_string(mode->getResolutionY()) + "@" + std::to_string(mode->getFps()));
        return false;
      }
    } else if (!mode) {
      logger()->warn("{}: neither {}x{}@{} nor {}x{}@{} is offered; keeping the sensor's mode", describe(),
                     options_.width, options_.height, options_.fps, kFallbackWidth, kFallbackHeight, kFallbackFps);
    }
    if (stream_->isPropertySupported(openni::STREAM_PROPERTY_MIRRORING) && stream_->getMirroringEnabled() &&
        stream_->setMirroringEnabled(false) != openni::STATUS_OK) {
      logger()->warn("{}: cannot turn mirroring off", describe());
    }
    return true;
  }

  std::string uri_;
  SourceOptions options_;
  std::shared_ptr<DeviceWatch> watch_;
  std::string open_uri_;
  int64_t last_frame_ns_ = 0;
};

// ---------------------------------------------------------------------------------------------
// .oni recording.

class OniRecording final : public OpenNi2SourceBase {
 public:
  OniRecording(std::string file, const SourceOptions& options) : file_(std::move(file)), options_(options) {}
  ~OniRecording() override { close(); }

  [[nodiscard]] std::string describe() const override { return "oni:" + file_; }
  [[nodiscard]] bool is_live() const override { return false; }

  GrabStatus grab(RawFrame& frame, std::chrono::milliseconds timeout) override {
    if (!stream_) return bad_frame("not open");
    if (ended_) return GrabStatus::kEndOfStream;
    switch (wait_ready(timeout, nullptr)) {
      case Wait::kReady:
        break;
      case Wait::kTimeout:
        // Normally the end is known from the frame count; without one, silence ends a recording.
        if (!options_.loop && frame_count_ == 0 && openni2::monotonic_ns() - last_frame_ns_ > kRecordingSilenceNs) {
          ended_ = true;
          return GrabStatus::kEndOfStream;
        }
        return GrabStatus::kTimeout;
      case Wait::kLost:
      case Wait::kError:
        return bad_frame(with_detail("waitForAnyStream failed"));
    }
    int index = 0;
    const GrabStatus status = read_ready_frame(frame, &index);
    if (status != GrabStatus::kFrame) return status;
    last_frame_ns_ = frame.capture_ns;
    ++frames_read_;
    // OniFile numbers a stream's frames 1..N. With repeat off nothing follows frame N (a
    // readFrame would block for ever), so the end is known from the count, not from a timeout.
    if (!options_.loop && frame_count_ > 0 && (index >= frame_count_ || frames_read_ >= frame_count_)) ended_ = true;
    return GrabStatus::kFrame;
  }

 private:
  bool open_impl(std::string* why) override {
    close();
    ended_ = false;
    frames_read_ = 0;
    frame_count_ = 0;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file_, ec)) {
      *why = "no such file";
      return false;
    }
    if (!std::ifstream(file_, std::ios::binary).good()) {
      *why = "cannot read the file";
      return false;
    }
    if (!runtime_) {
      runtime_ = Runtime::acquire(why);
      if (!runtime_) return false;
    }
    device_ = std::make_unique<openni::Device>();
    if (device_->open(file_.c_str()) != openni::STATUS_OK) {
      *why = with_detail("OpenNI2 cannot play it (not an .oni recording, or corrupt)");
      return false;
    }
    if (!device_->isFile() || device_->getPlaybackControl() == nullptr) {
      *why = "OpenNI2 did not open it as a recording";
      return false;
    }
    if (!open_depth_stream(why)) return false;
    last_frame_ns_ = openni2::monotonic_ns();
    logger()->info("{}: {} depth frames {}x{} at {} fps, f {:.1f}/{:.1f} px, depth unit {} mm{}{}", describe(),
                   frame_count_, camera_.width, camera_.height, camera_.fps, camera_.fx, camera_.fy,
                   camera_.depth_scale_mm, options_.loop ? ", looped" : "",
                   options_.as_fast_as_possible ? ", as fast as possible" : "");
    return true;
  }

  // Playback set before the stream starts: speed -1 ("manual": OpenNI2 hands out the next frame
  // when the reader waits for it, so none is dropped) when as fast as possible, else 1.0 (the
  // recording's own frame rate); repeat when looping, and also in manual playback of a recording
  // whose frame count is known. Without repeat, OniFile's player thread spins at the end of the
  // file over its list of streams, unlocked, and destroying our stream then crashes it (close()
  // after a manual playback to the end: 3 crashes in 40 reopen tests on a busy machine). With
  // repeat it rewinds and waits for the next read instead, and grab() still ends after
  // frame_count_ frames. At the recording's own rate repeat is no cure: the rewound frame 1 follows
  // the last frame at once and can replace it before it is read.
  bool configure(std::string* why) override {
    openni::PlaybackControl* playback = device_->getPlaybackControl();
    const float speed = options_.as_fast_as_possible ? -1.0F : 1.0F;
    if (playback->setSpeed(speed) != openni::STATUS_OK) {
      *why = with_detail("cannot set the playback speed");
      return false;
    }
    frame_count_ = std::max(0, playback->getNumberOfFrames(*stream_));
    const bool repeat = options_.loop || (options_.as_fast_as_possible && frame_count_ > 0);
    if (playback->setRepeatEnabled(repeat) != openni::STATUS_OK) {
      *why = with_detail("cannot set playback repeat");
      return false;
    }
    return true;
  }

  std::string file_;
  SourceOptions options_;
  int frame_count_ = 0;
  int frames_read_ = 0;
  int64_t last_frame_ns_ = 0;
  bool ended_ = false;
};

}  // namespace

std::unique_ptr<DepthSource> make_openni2_camera(const std::string& uri, const SourceOptions& options) {
  if (options.width <= 0 || options.height <= 0 || options.fps <= 0) {
    throw std::invalid_argument("openni2" + (uri.empty() ? std::string() : ":" + uri) +
                                ": depth mode must have a positive width, height and fps");
  }
  return std::make_unique<OpenNi2Camera>(uri, options);
}

std::unique_ptr<DepthSource> make_oni_recording(const std::string& file, const SourceOptions& options) {
  if (file.empty()) throw std::invalid_argument("oni: needs a file name (oni:FILE.oni)");
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw std::invalid_argument("oni:" + file + ": no such file");
  return std::make_unique<OniRecording>(file, options);
}

}  // namespace handtrack::daemon
