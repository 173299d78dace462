// handtrack/ipc/pose_ring_reader.hpp: a client's side of the shared-memory pose ring.
//
// Maps the segment read-only (the shm object may be mode 0640 and owned by another user) and
// never writes to it, so it can neither block nor corrupt the writer. It accepts a segment only
// from a trusted owner (root, its own user, the service user "handtrack", and the users in
// $HANDTRACK_TRUSTED_USERS) that no other user may write: anyone can create a name in /dev/shm
// (docs/SECURITY.md). Errors are status values
// (handtrack_status); nothing here throws except std::bad_alloc from open()'s strings.
//
// Thread role: one PoseRingReader is used by one thread at a time.
//
// Reattaching: the reader follows the name. When its segment was superseded by a new writer
// (the new writer flags the old segment), or the writer stopped or died (stale heartbeat), the
// waiting calls re-open the name and, if a segment with another epoch is there, switch to it and
// continue with that epoch's records from its first one still in the ring.
#pragma once

#include <handtrack/ipc/pose_record.hpp>
#include <handtrack/ipc/pose_ring_shm.hpp>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

namespace handtrack::ipc {

namespace detail {
class TrustedOwners;
}  // namespace detail

class PoseRingReader {
 public:
  PoseRingReader();
  ~PoseRingReader();
  PoseRingReader(PoseRingReader&&) noexcept;
  PoseRingReader& operator=(PoseRingReader&&) noexcept;

  // Maps `name` read-only, checks its owner and validates its header. On error the reader stays closed and
  // error_detail() says what did not match. Waiting starts after the newest record present now.
  Status open(const std::string& name);
  void close() noexcept;
  [[nodiscard]] bool is_open() const noexcept { return header_ != nullptr; }

  // Every read copies one whole frame record (all its hands, of one frame: one seqlock covers it);
  // hand_count is never above kMaxHands (a corrupt segment's count is clamped).
  // Copies the newest record (HANDTRACK_NO_RECORD if none yet). Never blocks, never waits.
  Status latest(FrameRecord& out) noexcept;
  // Copies the next record in order if it is there (HANDTRACK_TIMEOUT if not). Never blocks.
  Status try_next(FrameRecord& out) noexcept;
  // Waits up to `timeout` for the next record in order (see handtrack_wait_next).
  Status wait_next(FrameRecord& out, std::chrono::nanoseconds timeout) noexcept;
  // Waits up to `timeout` for a record newer than the last one returned; returns the newest.
  Status wait_latest(FrameRecord& out, std::chrono::nanoseconds timeout) noexcept;

  // The next record in order becomes the oldest one still in the ring (not the next new one).
  void rewind() noexcept;

  // Records skipped just before the last record returned, and in total since open().
  [[nodiscard]] std::uint64_t missed() const noexcept { return missed_; }
  [[nodiscard]] std::uint64_t missed_total() const noexcept { return missed_total_; }
  // Epoch of the segment currently mapped (0 when closed).
  [[nodiscard]] std::uint64_t epoch() const noexcept;

  // Fills `out` from the header: device state, liveness, epoch, heartbeat, statistics.
  Status writer_status(WriterStatus& out) noexcept;

  [[nodiscard]] const std::string& error_detail() const noexcept { return detail_; }

 private:
  enum class Mode { kNext, kLatest };
  Status wait(FrameRecord& out, std::chrono::nanoseconds timeout, Mode mode) noexcept;
  Status read_index(std::uint64_t index, FrameRecord& out) noexcept;
  Status writer_trouble(std::int64_t now_ns) const noexcept;  // OK, WRITER_DEAD or WRITER_STOPPED
  bool try_reattach() noexcept;  // true if now mapped to a segment with a new epoch
  Status map(const std::string& name, bool initial);
  void accept(std::uint64_t index) noexcept;

  struct Mapping;
  std::unique_ptr<Mapping> mapping_;
  std::unique_ptr<const detail::TrustedOwners> trusted_;  // read at open(), kept for reattaching
  const shm::Header* header_ = nullptr;
  const shm::Slot* slots_ = nullptr;
  std::uint32_t capacity_ = 0;
  std::uint64_t next_index_ = 0;  // next record to return in order
  bool have_last_ = false;        // last_index_ is valid
  std::uint64_t last_index_ = 0;  // index of the last record returned
  std::uint64_t missed_ = 0;
  std::uint64_t missed_total_ = 0;
  bool trouble_reported_ = false;  // WRITER_DEAD/STOPPED already returned once for this episode
  std::string name_;
  std::string detail_;
};

}  // namespace handtrack::ipc
