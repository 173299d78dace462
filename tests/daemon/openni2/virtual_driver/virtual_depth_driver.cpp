// handtrack's virtual OpenNI2 depth camera: a driver that OpenNI2 loads from its drivers
// directory like PS1080 or OniFile, so the OpenNI2 sources can be tested through the real
// OpenNI2 library without hardware (like libcamera's vimc).
//
// One device, URI "handtrack-virtual://depth0", a depth sensor offering 320x240@60 and
// 640x480@30 in 1 mm units, FOV 58 x 45 degrees (a PrimeSense-class sensor). Frames: a wall at
// kWallMm with a disc (a "hand") at kBlobMm circling in front of it.
//
// Stall: while the file named by $HANDTRACK_VDEV_STALL_FILE exists, streams deliver nothing but
// the device stays connected (a sensor that hangs, or a driver that misses the unplug).
//
// Unplug and replug: while the file named by $HANDTRACK_VDEV_PLUG_FILE exists the device is
// plugged in (without the variable it always is). The driver's own thread polls that path every
// kPollInterval and, like a USB driver, raises OpenNI2's deviceDisconnected/deviceConnected
// callbacks. An unplugged device stops delivering frames but its objects stay valid until OpenNI2
// closes them, and deviceOpen refuses while unplugged, as with a real sensor.
//
// Thread roles: OpenNI2 calls the driver from the application's threads; the poll thread and one
// frame thread per started stream are the driver's own. `Driver::mutex_` guards the open-device
// list; callbacks into OpenNI2 are never made while holding it (OpenNI2 takes its own locks and
// calls back into the driver, so holding ours would risk a lock-order inversion).

#include <cstdlib>
#include <new>

// OniDriverAPI.h's ONI_EXPORT_DRIVER uses XnLib's allocation macros, which Debian does not ship.
#define XN_NEW(type, arg) new (std::nothrow) type(arg)
#define XN_DELETE(p) delete (p)

#include <Driver/OniDriverAPI.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <sys/stat.h>

namespace handtrack::test::vdev {

namespace {

constexpr const char* kUri = "handtrack-virtual://depth0";
constexpr const char* kPlugFileEnv = "HANDTRACK_VDEV_PLUG_FILE";
constexpr const char* kStallFileEnv = "HANDTRACK_VDEV_STALL_FILE";
constexpr std::chrono::milliseconds kPollInterval{10};
constexpr float kHorizontalFovRad = 1.0122910F;  // 58 degrees
constexpr float kVerticalFovRad = 0.7853982F;    // 45 degrees
constexpr uint16_t kWallMm = 1800;
constexpr uint16_t kBlobMm = 600;
constexpr int kMaxDepthMm = 10000;

const OniVideoMode kModes[] = {
    {ONI_PIXEL_FORMAT_DEPTH_1_MM, 320, 240, 60},
    {ONI_PIXEL_FORMAT_DEPTH_1_MM, 640, 480, 30},
};

bool plug_file_exists(const std::string& path) {
  if (path.empty()) return true;
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

template <typename T>
OniStatus get_value(const T& value, void* data, int* size) {
  if (data == nullptr || size == nullptr || *size < static_cast<int>(sizeof(T))) return ONI_STATUS_BAD_PARAMETER;
  std::memcpy(data, &value, sizeof(T));
  *size = sizeof(T);
  return ONI_STATUS_OK;
}

template <typename T>
OniStatus set_value(T* value, const void* data, int size) {
  if (data == nullptr || size != static_cast<int>(sizeof(T))) return ONI_STATUS_BAD_PARAMETER;
  std::memcpy(value, data, sizeof(T));
  return ONI_STATUS_OK;
}

}  // namespace

class DepthStream final : public oni::driver::StreamBase {
 public:
  explicit DepthStream(const std::atomic<bool>* plugged) : plugged_(plugged) {
    const char* stall = std::getenv(kStallFileEnv);
    stall_file_ = stall ? stall : "";
  }
  ~DepthStream() override { stop(); }
  DepthStream(const DepthStream&) = delete;
  DepthStream& operator=(const DepthStream&) = delete;

  OniStatus start() override {
    std::lock_guard lock(mutex_);
    if (running_) return ONI_STATUS_OK;
    running_ = true;
    thread_ = std::thread([this] { run(); });
    return ONI_STATUS_OK;
  }

  void stop() override {
    {
      std::lock_guard lock(mutex_);
      if (!running_) return;
      running_ = false;
    }
    wake_.notify_all();
    thread_.join();
  }

  OniBool isPropertySupported(int id) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
      case ONI_STREAM_PROPERTY_MIRRORING:
      case ONI_STREAM_PROPERTY_MAX_VALUE:
      case ONI_STREAM_PROPERTY_MIN_VALUE:
      case ONI_STREAM_PROPERTY_STRIDE:
        return TRUE;
      default:
        return FALSE;
    }
  }

  OniStatus getProperty(int id, void* data, int* size) override {
    std::lock_guard lock(mutex_);
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
        return get_value(mode_, data, size);
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
        return get_value(kHorizontalFovRad, data, size);
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
        return get_value(kVerticalFovRad, data, size);
      case ONI_STREAM_PROPERTY_MIRRORING:
        return get_value(mirroring_, data, size);
      case ONI_STREAM_PROPERTY_MAX_VALUE:
        return get_value(kMaxDepthMm, data, size);
      case ONI_STREAM_PROPERTY_MIN_VALUE:
        return get_value(0, data, size);
      case ONI_STREAM_PROPERTY_STRIDE:
        return get_value(static_cast<int>(mode_.resolutionX * sizeof(OniDepthPixel)), data, size);
      default:
        return ONI_STATUS_NOT_SUPPORTED;
    }
  }

  OniStatus setProperty(int id, const void* data, int size) override {
    std::lock_guard lock(mutex_);
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE: {
        if (running_) return ONI_STATUS_OUT_OF_FLOW;
        OniVideoMode wanted{};
        if (set_value(&wanted, data, size) != ONI_STATUS_OK) return ONI_STATUS_BAD_PARAMETER;
        const bool offered = std::any_of(std::begin(kModes), std::end(kModes), [&](const OniVideoMode& m) {
          return m.pixelFormat == wanted.pixelFormat && m.resolutionX == wanted.resolutionX &&
                 m.resolutionY == wanted.resolutionY && m.fps == wanted.fps;
        });
        if (!offered) return ONI_STATUS_NOT_SUPPORTED;
        mode_ = wanted;
        return ONI_STATUS_OK;
      }
      case ONI_STREAM_PROPERTY_MIRRORING:
        return set_value(&mirroring_, data, size);
      default:
        return ONI_STATUS_NOT_SUPPORTED;
    }
  }

 private:
  void run() {
    std::unique_lock lock(mutex_);
    const auto period = std::chrono::microseconds(1'000'000 / std::max(1, mode_.fps));
    auto next = std::chrono::steady_clock::now();
    int index = 0;
    while (running_) {
      next += period;
      if (wake_.wait_until(lock, next, [this] { return !running_; })) break;
      if (!plugged_->load(std::memory_order_acquire)) continue;  // unplugged: the USB data stopped
      if (!stall_file_.empty() && plug_file_exists(stall_file_)) continue;  // hung sensor
      const OniVideoMode mode = mode_;
      const OniBool mirrored = mirroring_;
      lock.unlock();
      emit(mode, mirrored, ++index);
      lock.lock();
    }
  }

  // A wall with a disc circling in front of it (one turn every 2 s, radius a quarter of the height).
  void emit(const OniVideoMode& mode, OniBool mirrored, int index) {
    OniFrame* frame = getServices().acquireFrame();
    if (frame == nullptr) return;
    const int w = mode.resolutionX;
    const int h = mode.resolutionY;
    auto* depth = static_cast<OniDepthPixel*>(frame->data);
    const double phase = 2.0 * M_PI * index / (2.0 * mode.fps);
    double bx = 0.5 * w + 0.25 * h * std::cos(phase);
    const double by = 0.5 * h + 0.25 * h * std::sin(phase);
    if (mirrored) bx = w - 1 - bx;
    const double r2 = std::pow(0.1 * h, 2);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const double d2 = (u - bx) * (u - bx) + (v - by) * (v - by);
        depth[v * w + u] = d2 <= r2 ? kBlobMm : kWallMm;
      }
    }
    frame->dataSize = w * h * static_cast<int>(sizeof(OniDepthPixel));
    frame->sensorType = ONI_SENSOR_DEPTH;
    frame->timestamp = static_cast<uint64_t>(index) * 1'000'000ULL / static_cast<uint64_t>(mode.fps);
    frame->frameIndex = index;
    frame->width = w;
    frame->height = h;
    frame->videoMode = mode;
    frame->croppingEnabled = FALSE;
    frame->cropOriginX = 0;
    frame->cropOriginY = 0;
    frame->stride = w * static_cast<int>(sizeof(OniDepthPixel));
    raiseNewFrame(frame);
    getServices().releaseFrame(frame);
  }

  const std::atomic<bool>* plugged_;
  std::string stall_file_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread thread_;
  bool running_ = false;
  OniVideoMode mode_ = kModes[0];
  OniBool mirroring_ = FALSE;
};

class Device final : public oni::driver::DeviceBase {
 public:
  Device() {
    sensor_.sensorType = ONI_SENSOR_DEPTH;
    sensor_.numSupportedVideoModes = static_cast<int>(std::size(kModes));
    sensor_.pSupportedVideoModes = modes_;
    std::copy(std::begin(kModes), std::end(kModes), modes_);
  }

  OniStatus getSensorInfoList(OniSensorInfo** infos, int* count) override {
    *infos = &sensor_;
    *count = 1;
    return ONI_STATUS_OK;
  }

  oni::driver::StreamBase* createStream(OniSensorType type) override {
    if (type != ONI_SENSOR_DEPTH) return nullptr;
    return new (std::nothrow) DepthStream(&plugged_);
  }

  void destroyStream(oni::driver::StreamBase* stream) override { delete stream; }

  // The poll thread: the cable was pulled. Streams stop delivering; objects stay until closed.
  void unplug() { plugged_.store(false, std::memory_order_release); }

 private:
  std::atomic<bool> plugged_{true};
  OniVideoMode modes_[std::size(kModes)]{};
  OniSensorInfo sensor_{};
};

class Driver final : public oni::driver::DriverBase {
 public:
  explicit Driver(OniDriverServices* services) : DriverBase(services) {
    std::strncpy(info_.uri, kUri, sizeof(info_.uri) - 1);
    std::strncpy(info_.vendor, "handtrack", sizeof(info_.vendor) - 1);
    std::strncpy(info_.name, "virtual depth camera", sizeof(info_.name) - 1);
    info_.usbVendorId = 0;
    info_.usbProductId = 0;
  }
  ~Driver() override { shutdown(); }
  Driver(const Driver&) = delete;
  Driver& operator=(const Driver&) = delete;

  OniStatus initialize(oni::driver::DeviceConnectedCallback connected,
                       oni::driver::DeviceDisconnectedCallback disconnected,
                       oni::driver::DeviceStateChangedCallback state_changed, void* cookie) override {
    const OniStatus rc = DriverBase::initialize(connected, disconnected, state_changed, cookie);
    if (rc != ONI_STATUS_OK) return rc;
    const char* path = std::getenv(kPlugFileEnv);
    plug_file_ = path ? path : "";
    // Devices present at start are announced during initialize, as PS1080 does.
    plugged_ = plug_file_exists(plug_file_);
    if (plugged_) deviceConnected(&info_);
    running_ = true;
    poll_thread_ = std::thread([this] { poll(); });
    return ONI_STATUS_OK;
  }

  oni::driver::DeviceBase* deviceOpen(const char* uri, const char* /*mode*/) override {
    if (uri == nullptr || std::strcmp(uri, kUri) != 0) return nullptr;
    std::lock_guard lock(mutex_);
    if (!plugged_) return nullptr;
    auto* device = new (std::nothrow) Device();
    if (device) open_.push_back(device);
    return device;
  }

  void deviceClose(oni::driver::DeviceBase* device) override {
    std::lock_guard lock(mutex_);
    std::erase(open_, device);
    delete device;
  }

  OniStatus tryDevice(const char* /*uri*/) override { return ONI_STATUS_ERROR; }

  void shutdown() override {
    {
      std::lock_guard lock(mutex_);
      if (!running_) return;
      running_ = false;
    }
    wake_.notify_all();
    if (poll_thread_.joinable()) poll_thread_.join();
    std::lock_guard lock(mutex_);
    for (Device* d : open_) delete d;
    open_.clear();
  }

 private:
  void poll() {
    std::unique_lock lock(mutex_);
    while (running_) {
      if (wake_.wait_for(lock, kPollInterval, [this] { return !running_; })) break;
      const bool now = plug_file_exists(plug_file_);
      if (now == plugged_) continue;
      plugged_ = now;
      if (!now) {
        for (Device* d : open_) d->unplug();
      }
      lock.unlock();  // OpenNI2 locks its own state and may call back into deviceOpen/Close
      if (now) {
        deviceConnected(&info_);
      } else {
        deviceDisconnected(&info_);
      }
      lock.lock();
    }
  }

  OniDeviceInfo info_{};
  std::string plug_file_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread poll_thread_;
  bool running_ = false;
  bool plugged_ = false;
  std::vector<Device*> open_;
};

}  // namespace handtrack::test::vdev

ONI_EXPORT_DRIVER(handtrack::test::vdev::Driver)
