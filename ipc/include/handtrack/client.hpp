// handtrack/client.hpp: a header-only C++ RAII wrapper over the stable C API (handtrack/client.h).
// Links against the C library (handtrack::client), so applications get its ABI stability.
//
//   handtrack::Client client;
//   if (int st = client.open("handtrack"); st != HANDTRACK_OK) {
//     std::cerr << handtrack::Client::describe(st) << "\n";   // e.g. "no handtrack shared memory..."
//     return 1;
//   }
//   handtrack_pose pose;
//   for (;;) {
//     int st = client.wait_next(pose, std::chrono::seconds(1));
//     if (st == HANDTRACK_OK) use(pose, client.missed());
//     // HANDTRACK_TIMEOUT, _ERR_WRITER_DEAD, _ERR_WRITER_STOPPED: keep waiting; it reattaches itself
//   }
//
// handtrack::PoseFilter (below) smooths poses with the C API's One Euro filter; handtrack::Gestures
// turns them into gesture strengths and events.
//
// Status values, not exceptions: reading poses is a hot path (STYLE: "the ipc reader returns
// status values and never throws"). One Client belongs to one thread at a time.
#pragma once

#include <handtrack/client.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <utility>

namespace handtrack {

class Client {
 public:
  Client() = default;
  ~Client() { close(); }
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;
  Client(Client&& other) noexcept : handle_(std::exchange(other.handle_, nullptr)) {}
  Client& operator=(Client&& other) noexcept {
    if (this != &other) {
      close();
      handle_ = std::exchange(other.handle_, nullptr);
    }
    return *this;
  }

  // Maps `shm_name` read-only (closing any previous mapping).
  int open(const std::string& shm_name = HANDTRACK_DEFAULT_SHM_NAME) noexcept {
    close();
    return handtrack_open(shm_name.c_str(), &handle_);
  }
  void close() noexcept {
    if (handle_ != nullptr) handtrack_close(std::exchange(handle_, nullptr));
  }
  [[nodiscard]] bool is_open() const noexcept { return handle_ != nullptr; }

  int latest(handtrack_pose& out) noexcept { return handtrack_latest(handle_, &out); }
  int wait_next(handtrack_pose& out, std::chrono::nanoseconds timeout) noexcept {
    return handtrack_wait_next(handle_, &out, static_cast<std::int64_t>(timeout.count()));
  }
  int wait_latest(handtrack_pose& out, std::chrono::nanoseconds timeout) noexcept {
    return handtrack_wait_latest(handle_, &out, static_cast<std::int64_t>(timeout.count()));
  }
  int rewind() noexcept { return handtrack_rewind(handle_); }
  [[nodiscard]] std::uint64_t missed() const noexcept { return handtrack_missed(handle_); }
  [[nodiscard]] std::uint64_t missed_total() const noexcept { return handtrack_missed_total(handle_); }
  int writer_status(handtrack_writer_status& out) noexcept {
    return handtrack_writer_status_get(handle_, &out);
  }

  // "<strerror>: <detail of the last failure in this thread>".
  static std::string describe(int status) {
    std::string text = handtrack_strerror(status);
    const char* detail = handtrack_error_detail();
    if (status < 0 && detail != nullptr && detail[0] != '\0') text += std::string(": ") + detail;
    return text;
  }

  [[nodiscard]] handtrack_client* native_handle() const noexcept { return handle_; }

 private:
  handtrack_client* handle_ = nullptr;
};

// A One Euro filter over poses (handtrack_filter_*; docs/FILTER.md): one per hand.
//
//   handtrack::PoseFilter smooth;                 // the documented defaults
//   if (client.wait_next(pose, 1s) == HANDTRACK_OK) { smooth.apply(pose); use(pose); }
class PoseFilter {
 public:
  // Default parameters; a PoseFilter is always usable (an invalid `params` falls back to them and
  // ok() is false).
  PoseFilter() noexcept { handtrack_filter_new(nullptr, &handle_); }
  explicit PoseFilter(const handtrack_filter_params& params) noexcept {
    ok_ = handtrack_filter_new(&params, &handle_) == HANDTRACK_OK;
    if (!ok_) handtrack_filter_new(nullptr, &handle_);
  }
  ~PoseFilter() { handtrack_filter_free(handle_); }
  PoseFilter(const PoseFilter&) = delete;
  PoseFilter& operator=(const PoseFilter&) = delete;
  PoseFilter(PoseFilter&& other) noexcept : handle_(std::exchange(other.handle_, nullptr)), ok_(other.ok_) {}
  PoseFilter& operator=(PoseFilter&& other) noexcept {
    if (this != &other) {
      handtrack_filter_free(handle_);
      handle_ = std::exchange(other.handle_, nullptr);
      ok_ = other.ok_;
    }
    return *this;
  }

  static handtrack_filter_params defaults() noexcept {
    handtrack_filter_params p{};
    handtrack_filter_default_params(&p);
    return p;
  }
  [[nodiscard]] bool ok() const noexcept { return ok_ && handle_ != nullptr; }
  // Smooths `pose` in place.
  void apply(handtrack_pose& pose) noexcept { handtrack_filter_apply(handle_, &pose); }
  void reset() noexcept { handtrack_filter_reset(handle_); }

 private:
  handtrack_filter* handle_ = nullptr;
  bool ok_ = true;
};

// Gestures of one hand (handtrack_gesture*; docs/GESTURES.md): strengths and start/end events.
//
//   handtrack::Gestures gestures;
//   const handtrack_gesture_state& g = gestures.update(pose);
//   if (g.event[HANDTRACK_GESTURE_PINCH] == HANDTRACK_GESTURE_START) click();
class Gestures {
 public:
  Gestures() noexcept { handtrack_gestures_new(&handle_); }
  ~Gestures() { handtrack_gestures_free(handle_); }
  Gestures(const Gestures&) = delete;
  Gestures& operator=(const Gestures&) = delete;
  Gestures(Gestures&& other) noexcept : handle_(std::exchange(other.handle_, nullptr)), state_(other.state_) {}
  Gestures& operator=(Gestures&& other) noexcept {
    if (this != &other) {
      handtrack_gestures_free(handle_);
      handle_ = std::exchange(other.handle_, nullptr);
      state_ = other.state_;
    }
    return *this;
  }

  // The next pose of this hand, in order.
  const handtrack_gesture_state& update(const handtrack_pose& pose) noexcept {
    handtrack_gestures_update(handle_, &pose, &state_);
    return state_;
  }
  void reset() noexcept { handtrack_gestures_reset(handle_); }
  [[nodiscard]] const handtrack_gesture_state& state() const noexcept { return state_; }
  static const char* name(int gesture) noexcept { return handtrack_gesture_name(gesture); }

 private:
  handtrack_gestures* handle_ = nullptr;
  handtrack_gesture_state state_{};
};

}  // namespace handtrack
