// handtrack/client.hpp: a header-only C++ RAII wrapper over the stable C API (handtrack/client.h).
// Links against the C library (handtrack::client), so applications get its ABI stability.
//
//   handtrack::Client client;
//   if (int st = client.open("handtrack"); st != HANDTRACK_OK) {
//     std::cerr << handtrack::Client::describe(st) << "\n";   // e.g. "no handtrack shared memory..."
//     return 1;
//   }
//   handtrack_frame frame;
//   for (;;) {
//     int st = client.wait_next(frame, std::chrono::seconds(1));
//     if (st == HANDTRACK_OK)
//       for (const handtrack_hand& hand : handtrack::hands(frame)) use(hand, client.missed());
//     // HANDTRACK_TIMEOUT, _ERR_WRITER_DEAD, _ERR_WRITER_STOPPED: keep waiting; it reattaches itself
//   }
//
// handtrack::PoseFilter (below) smooths every hand of a frame with the C API's One Euro filter;
// handtrack::Gestures turns the hands into gesture strengths and events. C++17.
//
// Status values, not exceptions: reading poses is a hot path (STYLE: "the ipc reader returns
// status values and never throws"). One Client belongs to one thread at a time.
#pragma once

#include <handtrack/client.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>

namespace handtrack {

namespace detail {
// A C handle this object owns and frees with Free: move-only.
template <typename T, void (*Free)(T*)>
class Owned {
 public:
  Owned() = default;
  ~Owned() { reset(); }
  Owned(const Owned&) = delete;
  Owned& operator=(const Owned&) = delete;
  Owned(Owned&& other) noexcept : p_(std::exchange(other.p_, nullptr)) {}
  Owned& operator=(Owned&& other) noexcept {
    if (this != &other) {
      reset();
      p_ = std::exchange(other.p_, nullptr);
    }
    return *this;
  }
  void reset() noexcept {
    if (p_ != nullptr) Free(std::exchange(p_, nullptr));
  }
  [[nodiscard]] T* get() const noexcept { return p_; }
  T** out() noexcept { return &p_; }

 private:
  T* p_ = nullptr;
};
}  // namespace detail

// The hands of a frame (hands[0 .. hand_count-1]) as a range: range-for, size(), operator[].
class Hands {
 public:
  explicit Hands(const handtrack_frame& frame) noexcept
      : first_(frame.hands), count_(frame.hand_count < HANDTRACK_MAX_HANDS ? frame.hand_count : HANDTRACK_MAX_HANDS) {}
  [[nodiscard]] const handtrack_hand* begin() const noexcept { return first_; }
  [[nodiscard]] const handtrack_hand* end() const noexcept { return first_ + count_; }
  [[nodiscard]] std::size_t size() const noexcept { return count_; }
  [[nodiscard]] bool empty() const noexcept { return count_ == 0; }
  const handtrack_hand& operator[](std::size_t i) const noexcept { return first_[i]; }

 private:
  const handtrack_hand* first_;
  std::size_t count_;
};

inline Hands hands(const handtrack_frame& frame) noexcept { return Hands(frame); }

class Client {
 public:
  // Maps `shm_name` read-only (closing any previous mapping).
  int open(const std::string& shm_name = HANDTRACK_DEFAULT_SHM_NAME) noexcept {
    close();
    return handtrack_open(shm_name.c_str(), handle_.out());
  }
  void close() noexcept { handle_.reset(); }
  [[nodiscard]] bool is_open() const noexcept { return handle_.get() != nullptr; }

  // Each read copies one whole frame: every hand of it, all of the same frame.
  int latest(handtrack_frame& out) noexcept { return handtrack_latest(handle_.get(), &out); }
  int wait_next(handtrack_frame& out, std::chrono::nanoseconds timeout) noexcept {
    return handtrack_wait_next(handle_.get(), &out, static_cast<std::int64_t>(timeout.count()));
  }
  int wait_latest(handtrack_frame& out, std::chrono::nanoseconds timeout) noexcept {
    return handtrack_wait_latest(handle_.get(), &out, static_cast<std::int64_t>(timeout.count()));
  }
  int rewind() noexcept { return handtrack_rewind(handle_.get()); }
  [[nodiscard]] std::uint64_t missed() const noexcept { return handtrack_missed(handle_.get()); }
  [[nodiscard]] std::uint64_t missed_total() const noexcept { return handtrack_missed_total(handle_.get()); }
  int writer_status(handtrack_writer_status& out) noexcept {
    return handtrack_writer_status_get(handle_.get(), &out);
  }

  // "<strerror>: <detail of the last failure in this thread>".
  static std::string describe(int status) {
    std::string text = handtrack_strerror(status);
    const char* detail = handtrack_error_detail();
    if (status < 0 && detail != nullptr && detail[0] != '\0') text += std::string(": ") + detail;
    return text;
  }

  [[nodiscard]] handtrack_client* native_handle() const noexcept { return handle_.get(); }

 private:
  detail::Owned<handtrack_client, handtrack_close> handle_;
};


// A One Euro filter over the hands of a stream of frames (handtrack_filter_*; docs/FILTER.md):
// one per stream, each hand followed by its hand_id.
//
//   handtrack::PoseFilter smooth;                 // the documented defaults
//   if (client.wait_next(frame, 1s) == HANDTRACK_OK) { smooth.apply(frame); use(frame); }
class PoseFilter {
 public:
  // Default parameters; a PoseFilter is always usable (an invalid `params` falls back to them and
  // ok() is false).
  PoseFilter() noexcept { handtrack_filter_new(nullptr, handle_.out()); }
  explicit PoseFilter(const handtrack_filter_params& params) noexcept {
    ok_ = handtrack_filter_new(&params, handle_.out()) == HANDTRACK_OK;
    if (!ok_) handtrack_filter_new(nullptr, handle_.out());
  }

  static handtrack_filter_params defaults() noexcept {
    handtrack_filter_params p{};
    handtrack_filter_default_params(&p);
    return p;
  }
  [[nodiscard]] bool ok() const noexcept { return ok_ && handle_.get() != nullptr; }
  // Smooths every hand of `frame` in place.
  void apply(handtrack_frame& frame) noexcept { handtrack_filter_apply(handle_.get(), &frame); }
  void reset() noexcept { handtrack_filter_reset(handle_.get()); }

 private:
  detail::Owned<handtrack_filter, handtrack_filter_free> handle_;
  bool ok_ = true;
};

// Gestures of every hand of a stream of frames (handtrack_gesture*; docs/GESTURES.md): strengths
// and start/end events per hand, each hand followed by its hand_id; a hand that leaves ends its
// gestures.
//
//   handtrack::Gestures gestures;
//   for (const handtrack_gesture_state& g : gestures.update(frame))
//     if (g.event[HANDTRACK_GESTURE_PINCH] == HANDTRACK_GESTURE_START) click(g.hand_id);
class Gestures {
 public:
  // The states of one update: the frame's hands in its order, then the hands that left.
  class States {
   public:
    [[nodiscard]] const handtrack_gesture_state* begin() const noexcept { return states_; }
    [[nodiscard]] const handtrack_gesture_state* end() const noexcept { return states_ + count_; }
    [[nodiscard]] std::size_t size() const noexcept { return count_; }
    const handtrack_gesture_state& operator[](std::size_t i) const noexcept { return states_[i]; }

   private:
    friend class Gestures;
    handtrack_gesture_state states_[HANDTRACK_GESTURE_MAX_STATES]{};
    std::size_t count_ = 0;
  };

  Gestures() noexcept { handtrack_gestures_new(handle_.out()); }

  // The next frame, in order.
  const States& update(const handtrack_frame& frame) noexcept {
    const int n = handtrack_gestures_update(handle_.get(), &frame, states_.states_);
    states_.count_ = n > 0 ? static_cast<std::size_t>(n) : 0;
    return states_;
  }
  void reset() noexcept { handtrack_gestures_reset(handle_.get()); }
  [[nodiscard]] const States& states() const noexcept { return states_; }
  static const char* name(int gesture) noexcept { return handtrack_gesture_name(gesture); }

 private:
  detail::Owned<handtrack_gestures, handtrack_gestures_free> handle_;
  States states_;
};

}  // namespace handtrack
