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

}  // namespace handtrack
