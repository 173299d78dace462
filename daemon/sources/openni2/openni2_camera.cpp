// openni2 | openni2:URI: a live OpenNI2 camera (the first device, or the given URI), reopened after
// an unplug. See docs/OPENNI2.md.
#include "openni2_source_base.hpp"

#include "../source_factories.hpp"

#include <stdexcept>

namespace handtrack::daemon {

namespace {

using namespace openni2;

// Fallback mode when the requested one is not offered (PrimeSense/Kinect-class sensors' default).
constexpr int kFallbackWidth = 640;
constexpr int kFallbackHeight = 480;
constexpr int kFallbackFps = 30;
// A live camera without frames this long is closed and reopened (see stalled_device_gone).
constexpr int64_t kStallReopenNs = 3'000'000'000;

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
    const int64_t silent_ns = monotonic_ns() - last_frame_ns_;
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
    last_frame_ns_ = monotonic_ns();
    log().info("{}: opened {} ({}x{} at {} fps, f {:.1f}/{:.1f} px, depth unit {} mm)", describe(), chosen,
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
      log().warn("{}: neither {}x{}@{} nor {}x{}@{} is offered; keeping the sensor's mode", describe(),
                 options_.width, options_.height, options_.fps, kFallbackWidth, kFallbackHeight, kFallbackFps);
    }
    if (stream_->isPropertySupported(openni::STREAM_PROPERTY_MIRRORING) && stream_->getMirroringEnabled() &&
        stream_->setMirroringEnabled(false) != openni::STATUS_OK) {
      log().warn("{}: cannot turn mirroring off", describe());
    }
    return true;
  }

  std::string uri_;
  SourceOptions options_;
  std::shared_ptr<DeviceWatch> watch_;
  std::string open_uri_;
  int64_t last_frame_ns_ = 0;
};

}  // namespace

std::unique_ptr<DepthSource> make_openni2_camera(const std::string& uri, const SourceOptions& options) {
  if (options.width <= 0 || options.height <= 0 || options.fps <= 0) {
    throw std::invalid_argument("openni2" + (uri.empty() ? std::string() : ":" + uri) +
                                ": depth mode must have a positive width, height and fps");
  }
  return std::make_unique<OpenNi2Camera>(uri, options);
}

}  // namespace handtrack::daemon
