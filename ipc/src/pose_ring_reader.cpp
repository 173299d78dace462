// PoseRingReader: maps a segment read-only, reads records with the seqlock, waits on the futex.
#include <handtrack/ipc/pose_ring_reader.hpp>

#include "segment_owner.hpp"
#include "seqlock.hpp"

#include <boost/interprocess/mapped_region.hpp>
#include <boost/interprocess/shared_memory_object.hpp>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <thread>

namespace bip = boost::interprocess;

namespace handtrack::ipc {

struct PoseRingReader::Mapping {
  bip::mapped_region region;
};

namespace {

// Bounded retries when the writer laps a slot during our copy (needs `capacity` publishes during
// one 1336-byte copy, so in practice never more than one retry).
constexpr int kReadAttempts = 16;
// open() retries while the writer is between shm_open and publishing the magic (microseconds).
constexpr int kNotReadyAttempts = 20;
constexpr auto kNotReadyRetryDelay = std::chrono::milliseconds(1);

}  // namespace

PoseRingReader::PoseRingReader() = default;
PoseRingReader::~PoseRingReader() = default;
PoseRingReader::PoseRingReader(PoseRingReader&&) noexcept = default;
PoseRingReader& PoseRingReader::operator=(PoseRingReader&&) noexcept = default;

Status PoseRingReader::map(const std::string& name, bool initial) {
  std::string detail;
  Status status = HANDTRACK_OK;
  for (int attempt = 0; attempt < (initial ? kNotReadyAttempts : 1); ++attempt) {
    if (attempt > 0) std::this_thread::sleep_for(kNotReadyRetryDelay);
    bip::shared_memory_object object;
    try {
      object = bip::shared_memory_object(bip::open_only, name.c_str(), bip::read_only);
    } catch (const bip::interprocess_exception& e) {
      const int err = e.get_native_error();
      if (err == ENOENT) {
        status = HANDTRACK_ERR_NOT_FOUND;
        detail = "no shared memory object '/" + name + "' (is handtrackd running?)";
      } else if (err == EACCES || err == EPERM) {
        status = HANDTRACK_ERR_PERMISSION;
        detail = "not allowed to open '/" + name + "' (not in the daemon's group?)";
      } else {
        status = HANDTRACK_ERR_SYSTEM;
        detail = "cannot open '/" + name + "': " + e.what();
      }
      break;
    }
    if (const std::string why = detail::untrusted_reason(object.get_mapping_handle().handle, *trusted_);
        !why.empty()) {
      status = HANDTRACK_ERR_UNTRUSTED_OWNER;
      detail = "'/" + name + "' refused: " + why;
      break;
    }
    bip::offset_t size = 0;
    if (!object.get_size(size)) {
      status = HANDTRACK_ERR_SYSTEM;
      detail = "cannot stat '/" + name + "': " + std::strerror(errno);
      break;
    }
    if (size == 0) {
      status = HANDTRACK_ERR_NOT_READY;
      detail = "'/" + name + "' is empty (writer still creating it)";
      continue;
    }
    auto mapping = std::make_unique<Mapping>();
    try {
      mapping->region =
          bip::mapped_region(object, bip::read_only, 0, static_cast<std::size_t>(size));
    } catch (const bip::interprocess_exception& e) {
      status = HANDTRACK_ERR_SYSTEM;
      detail = "cannot map '/" + name + "': " + e.what();
      break;
    }
    status = shm::validate_segment(mapping->region.get_address(), mapping->region.get_size(),
                                   &detail);
    if (status == HANDTRACK_ERR_NOT_READY) continue;
    if (status != HANDTRACK_OK) {
      detail = "'/" + name + "': " + detail;
      break;
    }
    if (!initial && header_ != nullptr &&
        static_cast<const shm::Header*>(mapping->region.get_address())->epoch == header_->epoch) {
      return HANDTRACK_ERR_NOT_FOUND;  // the same segment: nothing new to attach to
    }
    mapping_ = std::move(mapping);
    auto* base = static_cast<const unsigned char*>(mapping_->region.get_address());
    header_ = reinterpret_cast<const shm::Header*>(base);
    slots_ = reinterpret_cast<const shm::Slot*>(base + sizeof(shm::Header));
    capacity_ = header_->capacity;
    // A fresh client waits for records after the newest present; a reattaching one reads the new
    // epoch from its start (what is still in the ring).
    // SYNC: acquire; pairs with the writer's release store of head.
    next_index_ = initial ? header_->head.load(std::memory_order_acquire) : 0;
    have_last_ = false;
    trouble_reported_ = false;
    name_ = name;
    return HANDTRACK_OK;
  }
  if (initial) detail_ = detail;
  return status;
}

Status PoseRingReader::open(const std::string& name) {
  close();
  detail_.clear();
  missed_ = missed_total_ = 0;
  if (name.empty() || name.find('/') != std::string::npos) {
    detail_ = "invalid shared memory name '" + name + "'";
    return HANDTRACK_ERR_INVALID_ARGUMENT;
  }
  std::string trust_error;
  trusted_ = std::make_unique<const detail::TrustedOwners>(detail::TrustedOwners::from_environment(&trust_error));
  if (!trust_error.empty()) {
    detail_ = trust_error;
    return HANDTRACK_ERR_INVALID_ARGUMENT;
  }
  return map(name, true);
}

void PoseRingReader::close() noexcept {
  mapping_.reset();
  header_ = nullptr;
  slots_ = nullptr;
  capacity_ = 0;
}

void PoseRingReader::rewind() noexcept {
  if (header_ == nullptr) return;
  // SYNC: acquire; pairs with the writer's release store of head. Slot head % capacity may be
  // rewritten right now, so the oldest safe record is head - capacity + 1.
  const std::uint64_t head = header_->head.load(std::memory_order_acquire);
  next_index_ = head >= capacity_ ? head - capacity_ + 1 : 0;
}

std::uint64_t PoseRingReader::epoch() const noexcept {
  return header_ != nullptr ? header_->epoch : 0;
}

void PoseRingReader::accept(std::uint64_t index) noexcept {
  missed_ = index > next_index_ ? index - next_index_ : 0;
  missed_total_ += missed_;
  next_index_ = std::max(next_index_, index + 1);
  have_last_ = true;
  last_index_ = index;
}

Status PoseRingReader::read_index(std::uint64_t index, FrameRecord& out) noexcept {
  const shm::Slot& slot = slots_[index % capacity_];
  switch (detail::seqlock_read(slot.seq, slot.words, &out, shm::kRecordWords, 2 * index + 2)) {
    case detail::SeqRead::kOk:
      // Callers loop over hands[0 .. hand_count-1]: a corrupt count must not take them past the end.
      out.hand_count = std::min(out.hand_count, kMaxHands);
      return HANDTRACK_OK;
    case detail::SeqRead::kNotYet: return HANDTRACK_TIMEOUT;
    case detail::SeqRead::kGone: break;
  }
  return HANDTRACK_ERR_BUSY;
}

Status PoseRingReader::latest(FrameRecord& out) noexcept {
  if (header_ == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  // SYNC: relaxed: a hint to re-open the name; the new segment is validated with acquire.
  if (header_->superseded.load(std::memory_order_relaxed) != 0) try_reattach();
  for (int attempt = 0; attempt < kReadAttempts; ++attempt) {
    // SYNC: acquire; pairs with the writer's release store of head (record head-1 is complete).
    const std::uint64_t head = header_->head.load(std::memory_order_acquire);
    if (head == 0) return HANDTRACK_NO_RECORD;
    if (read_index(head - 1, out) == HANDTRACK_OK) {
      accept(head - 1);
      return HANDTRACK_OK;
    }
    // Lapped during the copy: a newer record exists, read that one.
  }
  return HANDTRACK_ERR_BUSY;
}

Status PoseRingReader::try_next(FrameRecord& out) noexcept {
  if (header_ == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  const std::uint64_t wanted = next_index_;
  std::uint64_t index = wanted;
  for (int attempt = 0; attempt < kReadAttempts; ++attempt) {
    const Status status = read_index(index, out);
    if (status == HANDTRACK_OK) {
      next_index_ = wanted;
      accept(index);
      return HANDTRACK_OK;
    }
    // Not written yet (after a jump: the next call jumps again and counts the skip then).
    if (status == HANDTRACK_TIMEOUT) return HANDTRACK_TIMEOUT;
    // Overwritten: jump to the oldest record that is safely in the ring. Slot head % capacity may
    // be being rewritten right now, so the oldest safe one is head - capacity + 1.
    // SYNC: acquire; pairs with the writer's release store of head.
    const std::uint64_t head = header_->head.load(std::memory_order_acquire);
    const std::uint64_t oldest = head >= capacity_ ? head - capacity_ + 1 : 0;
    index = std::max(index + 1, oldest);
  }
  return HANDTRACK_ERR_BUSY;
}

Status PoseRingReader::writer_trouble(std::int64_t now_ns) const noexcept {
  // SYNC: relaxed loads: liveness estimates; the futex word's acquire load (in wait) or a fresh
  // mapping's validation orders them enough for a status report.
  if (header_->device_state.load(std::memory_order_relaxed) ==
      static_cast<std::uint32_t>(DeviceState::kStopped)) {
    return HANDTRACK_ERR_WRITER_STOPPED;
  }
  const std::int64_t age =
      detail::heartbeat_age_ns(now_ns, header_->heartbeat_ns.load(std::memory_order_relaxed));
  if (age > detail::dead_after_ns(header_->heartbeat_period_ns, shm::kDeadAfterHalfPeriods)) {
    return HANDTRACK_ERR_WRITER_DEAD;
  }
  return HANDTRACK_OK;
}

bool PoseRingReader::try_reattach() noexcept {
  if (name_.empty()) return false;
  try {
    return map(name_, false) == HANDTRACK_OK;
  } catch (...) {  // std::bad_alloc from a string: stay on the old segment
    return false;
  }
}

Status PoseRingReader::wait(FrameRecord& out, std::chrono::nanoseconds timeout,
                            Mode mode) noexcept {
  if (header_ == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  const std::int64_t start = detail::monotonic_ns();
  // Timeouts beyond ~290 years are "forever" (and must not overflow the deadline).
  const std::int64_t deadline =
      start + std::clamp<std::int64_t>(timeout.count(), 0, std::int64_t{1} << 62);
  std::int64_t last_reattach_ns = start - header_->heartbeat_period_ns;
  for (;;) {
    // SYNC: acquire; pairs with the writer's release RMW on the word after each publish and state
    // change. If the writer bumps the word after this load, FUTEX_WAIT below returns at once (the
    // kernel re-checks the value); if before, this load sees the bump and so (by the pairing) the
    // record or state it announced: a wake-up is never lost.
    const std::uint32_t word = header_->futex_word.load(std::memory_order_acquire);
    Status status;
    if (mode == Mode::kNext) {
      status = try_next(out);
    } else {
      // SYNC: acquire; pairs with the writer's release store of head.
      const std::uint64_t head = header_->head.load(std::memory_order_acquire);
      status = (head > next_index_) ? latest(out) : HANDTRACK_TIMEOUT;
    }
    if (status == HANDTRACK_OK) {
      trouble_reported_ = false;
      return HANDTRACK_OK;
    }
    if (status != HANDTRACK_TIMEOUT) return status;

    std::int64_t now = detail::monotonic_ns();
    const bool superseded = header_->superseded.load(std::memory_order_relaxed) != 0;
    Status trouble = writer_trouble(now);
    if (superseded || trouble != HANDTRACK_OK) {
      // Re-open the name: at once when superseded, else at most every half heartbeat period.
      if (superseded || now - last_reattach_ns >= header_->heartbeat_period_ns / 2) {
        last_reattach_ns = now;
        if (try_reattach()) continue;  // a new writer: read its records
      }
      if (trouble != HANDTRACK_OK && !trouble_reported_) {
        trouble_reported_ = true;
        return trouble;
      }
    } else {
      trouble_reported_ = false;
    }
    now = detail::monotonic_ns();
    if (now >= deadline) return trouble != HANDTRACK_OK ? trouble : HANDTRACK_TIMEOUT;
    std::int64_t sleep_ns = deadline - now;
    const std::int64_t period = header_->heartbeat_period_ns;
    if (trouble == HANDTRACK_OK) {
      // Wake when the heartbeat would turn stale, to report a dead writer on time.
      const std::int64_t age =
          detail::heartbeat_age_ns(now, header_->heartbeat_ns.load(std::memory_order_relaxed));
      const std::int64_t until_stale =
          detail::dead_after_ns(period, shm::kDeadAfterHalfPeriods) + 1'000'000 - age;
      sleep_ns = std::min(sleep_ns, std::max<std::int64_t>(until_stale, 1'000'000));
    } else {
      sleep_ns = std::min(sleep_ns, period / 2);  // poll the name for a new writer
    }
    detail::futex_wait(&header_->futex_word, word, sleep_ns);
  }
}

Status PoseRingReader::wait_next(FrameRecord& out, std::chrono::nanoseconds timeout) noexcept {
  return wait(out, timeout, Mode::kNext);
}

Status PoseRingReader::wait_latest(FrameRecord& out, std::chrono::nanoseconds timeout) noexcept {
  return wait(out, timeout, Mode::kLatest);
}

Status PoseRingReader::writer_status(WriterStatus& out) noexcept {
  if (header_ == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  if (header_->superseded.load(std::memory_order_relaxed) != 0) try_reattach();
  out = WriterStatus{};
  const std::int64_t now = detail::monotonic_ns();
  // SYNC: relaxed loads: a status snapshot, fields need not be mutually consistent.
  out.device_state = static_cast<std::int32_t>(header_->device_state.load(std::memory_order_relaxed));
  out.alive = writer_trouble(now) == HANDTRACK_OK ? 1 : 0;
  out.writer_pid = header_->writer_pid;
  out.capacity = capacity_;
  out.epoch = header_->epoch;
  out.records_published = header_->head.load(std::memory_order_acquire);
  out.heartbeat_ns = header_->heartbeat_ns.load(std::memory_order_relaxed);
  out.heartbeat_age_ns = detail::heartbeat_age_ns(now, out.heartbeat_ns);
  out.heartbeat_period_ns = header_->heartbeat_period_ns;
  for (int attempt = 0; attempt < kReadAttempts; ++attempt) {
    // The stats seqlock: same protocol as a slot; the version we want is whatever is current.
    const std::uint64_t seq = header_->stats_seq.load(std::memory_order_relaxed);
    if (seq % 2 != 0) {
      std::this_thread::yield();
      continue;
    }
    if (detail::seqlock_read(header_->stats_seq, header_->stats_words, &out.stats,
                             shm::kStatsWords, seq) == detail::SeqRead::kOk) {
      return HANDTRACK_OK;
    }
  }
  out.stats = RingStats{};
  return HANDTRACK_ERR_BUSY;
}

}  // namespace handtrack::ipc
