#include "openni2_runtime.hpp"

#include "logging.hpp"

#include <OpenNI.h>

#include <algorithm>
#include <cstring>
#include <ctime>

namespace handtrack::daemon::openni2 {

namespace {

// SYNC: `registry_mutex` guards `g_runtime` (who holds OpenNI2 now); `init_mutex` serialises
// OpenNI::initialize/shutdown and listener (un)registration, whose counters in OpenNI2 are not
// thread-safe. Lock order: registry_mutex, then init_mutex; ~Runtime takes init_mutex alone.
std::mutex& registry_mutex() {
  static std::mutex m;
  return m;
}
std::mutex& init_mutex() {
  static std::mutex m;
  return m;
}
std::weak_ptr<Runtime>& current_runtime() {
  static std::weak_ptr<Runtime> r;
  return r;
}

}  // namespace

struct Runtime::Listeners final : openni::OpenNI::DeviceConnectedListener,
                                  openni::OpenNI::DeviceDisconnectedListener,
                                  openni::OpenNI::DeviceStateChangedListener {
  explicit Listeners(Runtime* owner) : runtime(owner) {}
  void onDeviceConnected(const openni::DeviceInfo* info) override { runtime->on_connected(info->getUri()); }
  void onDeviceDisconnected(const openni::DeviceInfo* info) override {
    runtime->on_disconnected(info->getUri());
  }
  void onDeviceStateChanged(const openni::DeviceInfo* info, openni::DeviceState state) override {
    if (state == openni::DEVICE_STATE_ERROR) runtime->on_error_state(info->getUri());
  }
  Runtime* runtime;
  bool registered = false;
};

Runtime::Runtime() : listeners_(std::make_unique<Listeners>(this)) {}

bool Runtime::start(std::string* why) {
  std::lock_guard init_lock(init_mutex());
  const openni::Status rc = openni::OpenNI::initialize();
  if (rc != openni::STATUS_OK) {
    const std::string detail = openni::OpenNI::getExtendedError();
    // initialize() counts calls even when it fails: balance it.
    openni::OpenNI::shutdown();
    if (why) *why = "OpenNI2 initialize failed" + (detail.empty() ? std::string() : ": " + detail);
    return false;
  }
  initialized_ = true;
  if (openni::OpenNI::addDeviceConnectedListener(listeners_.get()) == openni::STATUS_OK &&
      openni::OpenNI::addDeviceDisconnectedListener(listeners_.get()) == openni::STATUS_OK &&
      openni::OpenNI::addDeviceStateChangedListener(listeners_.get()) == openni::STATUS_OK) {
    listeners_->registered = true;
  } else {
    log().warn("OpenNI2: could not register device event listeners; unplug is detected by timeouts only");
  }
  const openni::Version v = openni::OpenNI::getVersion();
  log().info("OpenNI2 {}.{}.{}.{} initialized", v.major, v.minor, v.maintenance, v.build);
  return true;
}

Runtime::~Runtime() {
  if (!initialized_) return;
  std::lock_guard init_lock(init_mutex());
  // Unregister before shutdown: the listeners die with this object, OpenNI2's event lists don't.
  openni::OpenNI::removeDeviceConnectedListener(listeners_.get());
  openni::OpenNI::removeDeviceDisconnectedListener(listeners_.get());
  openni::OpenNI::removeDeviceStateChangedListener(listeners_.get());
  openni::OpenNI::shutdown();
}

std::shared_ptr<Runtime> Runtime::acquire(std::string* why) {
  std::shared_ptr<Runtime> failed;  // destroyed after the lock is released
  std::lock_guard lock(registry_mutex());
  if (auto alive = current_runtime().lock()) return alive;
  std::shared_ptr<Runtime> fresh(new Runtime());
  if (!fresh->start(why)) {
    failed = std::move(fresh);
    return nullptr;
  }
  current_runtime() = fresh;
  return fresh;
}

void Runtime::add_watch(const std::shared_ptr<DeviceWatch>& watch) {
  std::lock_guard lock(watch_mutex_);
  std::erase_if(watches_, [](const std::weak_ptr<DeviceWatch>& w) { return w.expired(); });
  watches_.push_back(watch);
}

std::vector<std::string> Runtime::device_uris() {
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  std::vector<std::string> uris;
  uris.reserve(static_cast<size_t>(devices.getSize()));
  for (int i = 0; i < devices.getSize(); ++i) uris.emplace_back(devices[i].getUri());
  return uris;
}

void Runtime::on_connected(const char* uri) {
  // A waiting camera source finds the new device by itself: its open() is retried every second.
  log().info("OpenNI2: device connected: {}", uri ? uri : "?");
}

void Runtime::on_disconnected(const char* uri) {
  log().info("OpenNI2: device disconnected: {}", uri ? uri : "?");
  on_error_state(uri);
}

void Runtime::on_error_state(const char* uri) {
  if (uri == nullptr) return;
  std::lock_guard lock(watch_mutex_);
  for (const auto& weak : watches_) {
    auto watch = weak.lock();
    if (!watch) continue;
    std::lock_guard uri_lock(watch->uri_mutex);
    // SYNC: release pairs with the grab thread's acquire load of `lost`; the grab thread then
    // only closes the device, so no other data needs to be published with it.
    if (!watch->uri.empty() && watch->uri == uri) watch->lost.store(true, std::memory_order_release);
  }
}

}  // namespace handtrack::daemon::openni2
