// handtrack/ipc/pose_ring_writer.hpp: the daemon's side of the shared-memory pose ring.
//
//   using namespace handtrack::ipc;
//   PoseRingWriter ring(PoseRingWriter::Options{.name = "handtrack", .capacity = 256});
//   ring.set_device_state(DeviceState::kStreaming);
//   for (;;) {
//     FrameRecord frame{};  ... fill frame, capture_ns, timings, hand_count, hands[] ...
//     ring.publish(frame);         // stamps epoch and publish_ns, wakes waiting clients
//     ring.heartbeat();            // also call it when idle, at least every heartbeat_period
//     ring.set_stats(stats);       // about once a second
//   }
//   ring.mark_stopped();           // also done by the destructor
//
// Thread roles: publish() is called by one thread (the pipeline's publisher); set_stats() by one
// thread (may be another); heartbeat(), set_device_state() and mark_stopped() by any thread.
// Nothing here allocates, locks or blocks after construction; no reader can slow publish() down
// (readers map the segment read-only and never write to it).
#pragma once

#include <handtrack/ipc/pose_record.hpp>
#include <handtrack/ipc/pose_ring_shm.hpp>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace handtrack::ipc {

class PoseRingWriter {
 public:
  struct Options {
    std::string name = kDefaultShmName;  // shm_open name, without the leading '/'
    std::uint32_t capacity = 256;        // records in the ring (>= 2); ~4 s at 60 fps
    std::chrono::nanoseconds heartbeat_period = std::chrono::milliseconds(100);
    unsigned mode = 0640;                // file mode: group members may read; never group/other write
    // Take the name over even when another writer's heartbeat is fresh and its pid exists.
    bool replace_live_writer = false;
    // Tests only: called inside publish() between the two sequence stores of a slot (the slot
    // holds a half-written record), with the record's index. Null in production.
    void (*test_hook_mid_publish)(std::uint64_t index) = nullptr;
  };

  // Creates the segment `options.name`: replaces a stale one (its writer is dead or stopped, or
  // it is not a valid handtrack segment) and removes one of another user without ever mapping it
  // (that fails, naming the owner, when this user may not remove it: /dev/shm is sticky), reserves all its memory (posix_fallocate: a full
  // /dev/shm fails here, not with SIGBUS later), sets the mode, picks an epoch greater than the
  // replaced segment's and not smaller than the wall clock in microseconds, and marks the old
  // segment superseded so its readers reattach at once. Throws std::runtime_error naming the
  // segment and the failed step (invalid options, live writer present, no space, no permission).
  explicit PoseRingWriter(const Options& options);
  ~PoseRingWriter();  // mark_stopped(); the segment stays so clients see "stopped", not "missing"
  PoseRingWriter(const PoseRingWriter&) = delete;
  PoseRingWriter& operator=(const PoseRingWriter&) = delete;

  // Copies `frame` (all its hands) into the next slot (overwriting the oldest), stamping epoch and
  // publish_ns (CLOCK_MONOTONIC), counts as a heartbeat, and wakes waiting readers (FUTEX_WAKE).
  void publish(const FrameRecord& frame) noexcept;
  // Proves the writer alive; call at least once per heartbeat_period even when no frame arrives.
  void heartbeat() noexcept;
  void set_device_state(DeviceState state) noexcept;
  void set_stats(const RingStats& stats) noexcept;
  // Device state "stopped" and a wake-up, so readers report HANDTRACK_ERR_WRITER_STOPPED at once.
  void mark_stopped() noexcept;

  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[nodiscard]] std::uint64_t epoch() const noexcept { return epoch_; }
  [[nodiscard]] std::uint32_t capacity() const noexcept { return capacity_; }
  [[nodiscard]] std::uint64_t published() const noexcept { return next_index_; }
  [[nodiscard]] std::chrono::nanoseconds heartbeat_period() const noexcept { return heartbeat_period_; }
  // The epoch of the valid segment this writer replaced, if there was one (for the daemon's log).
  [[nodiscard]] std::optional<std::uint64_t> replaced_epoch() const noexcept { return replaced_epoch_; }
  // Who owned the object of another user that this writer removed from its name (empty: none).
  [[nodiscard]] const std::string& removed_foreign_owner() const noexcept { return removed_foreign_owner_; }

  // Removes the name (shm_unlink); mapped readers keep their mapping. True if it existed.
  static bool remove(const std::string& name) noexcept;

 private:
  struct Mapping;
  std::unique_ptr<Mapping> mapping_;
  shm::Header* header_ = nullptr;
  shm::Slot* slots_ = nullptr;
  std::string name_;
  std::uint32_t capacity_ = 0;
  std::uint64_t epoch_ = 0;
  std::uint64_t next_index_ = 0;  // index of the next record; only publish()'s thread touches it
  std::uint64_t stats_version_ = 0;  // stats seqlock count; only set_stats()'s thread touches it
  std::chrono::nanoseconds heartbeat_period_{};
  std::optional<std::uint64_t> replaced_epoch_;
  std::string removed_foreign_owner_;
  void (*test_hook_mid_publish_)(std::uint64_t) = nullptr;
};

}  // namespace handtrack::ipc
