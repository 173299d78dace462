#pragma once
// The process-wide OpenNI2 runtime: OpenNI::initialize() once for every source in the process,
// OpenNI::shutdown() when the last one lets go, and OpenNI2's device events (connected,
// disconnected, state changed) turned into per-source "device lost" flags.
//
// Thread roles: thread-safe (Runtime::acquire and the DeviceWatch registry). OpenNI2 raises
// device events on its drivers' own threads (USB event thread, a virtual driver's poll thread):
// the listeners only take `watch_mutex_` and set atomics, never call back into OpenNI2, so they
// cannot deadlock against a grab thread that is inside OpenNI2.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace handtrack::daemon::openni2 {

// What a live source learns from OpenNI2's device events about the device it has open.
struct DeviceWatch {
  std::mutex uri_mutex;
  std::string uri;                    // the open device's URI; empty: none open
  std::atomic<bool> lost{false};      // the device went away (disconnected or in error)
};

class Runtime {
 public:
  // Initializes OpenNI2 if no one holds it yet. nullptr with *why set when initialize() fails
  // (no drivers found, ...). Holders keep OpenNI2 initialized; the last one to go shuts it down.
  static std::shared_ptr<Runtime> acquire(std::string* why);

  ~Runtime();
  Runtime(const Runtime&) = delete;
  Runtime& operator=(const Runtime&) = delete;

  // Device events are delivered to `watch` until it is dropped (the registry holds it weakly).
  void add_watch(const std::shared_ptr<DeviceWatch>& watch);

  // URIs of the devices OpenNI2 knows right now (openni::OpenNI::enumerateDevices()).
  [[nodiscard]] static std::vector<std::string> device_uris();

  // Called by the listeners (OpenNI2's threads).
  void on_connected(const char* uri);
  void on_disconnected(const char* uri);
  void on_error_state(const char* uri);

 private:
  struct Listeners;
  Runtime();
  bool start(std::string* why);

  std::unique_ptr<Listeners> listeners_;
  bool initialized_ = false;
  std::mutex watch_mutex_;
  std::vector<std::weak_ptr<DeviceWatch>> watches_;
};

}  // namespace handtrack::daemon::openni2
