// PoseRingWriter: creates the segment, owns the name, publishes records.
#include <handtrack/ipc/pose_ring_writer.hpp>

#include "segment_owner.hpp"
#include "seqlock.hpp"

#include <boost/interprocess/mapped_region.hpp>
#include <boost/interprocess/shared_memory_object.hpp>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>
#include <stdexcept>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>

namespace bip = boost::interprocess;

namespace handtrack::ipc {

struct PoseRingWriter::Mapping {
  bip::shared_memory_object object;
  bip::mapped_region region;
};

namespace {

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw std::runtime_error("shared memory '/" + name + "': " + what);
}

// What we learn from a segment already bearing the name.
struct Previous {
  bool exists = false;
  std::optional<uid_t> foreign_owner;  // owned by another user: never mapped, never written
  bool valid = false;       // a handtrack segment of our ABI
  bool live = false;        // its writer looks alive
  std::uint64_t epoch = 0;
  std::int32_t pid = 0;
  std::unique_ptr<bip::mapped_region> region;  // kept (read-write) to flag it superseded
};

bool pid_exists(std::int32_t pid) {
  if (pid <= 0) return false;
  return ::kill(pid, 0) == 0 || errno == EPERM;
}

Previous inspect_previous(const std::string& name) {
  Previous prev;
  try {
    const bip::shared_memory_object peek(bip::open_only, name.c_str(), bip::read_only);
    uid_t owner = 0;
    if (detail::owner_of(peek.get_mapping_handle().handle, &owner) && owner != ::geteuid()) {
      prev.exists = true;
      prev.foreign_owner = owner;
      return prev;
    }
  } catch (const bip::interprocess_exception& e) {
    if (e.get_native_error() == ENOENT) return prev;
    // Not even readable: another user's (mode 0600, say). glibc keeps the names in /dev/shm.
    prev.exists = true;
    struct stat st {};
    if (::stat(("/dev/shm/" + name).c_str(), &st) == 0 && st.st_uid != ::geteuid()) prev.foreign_owner = st.st_uid;
    return prev;
  }
  std::unique_ptr<bip::shared_memory_object> object;
  try {
    object = std::make_unique<bip::shared_memory_object>(bip::open_only, name.c_str(),
                                                         bip::read_write);
  } catch (const bip::interprocess_exception& e) {
    if (e.get_native_error() == ENOENT) return prev;
    prev.exists = true;  // e.g. EACCES: we will try to unlink it and fail with a clear message
    return prev;
  }
  prev.exists = true;
  bip::offset_t size = 0;
  if (!object->get_size(size) || size < static_cast<bip::offset_t>(sizeof(shm::Header))) return prev;
  try {
    prev.region = std::make_unique<bip::mapped_region>(*object, bip::read_write, 0,
                                                       static_cast<std::size_t>(size));
  } catch (const bip::interprocess_exception&) {
    return prev;
  }
  if (shm::validate_segment(prev.region->get_address(), prev.region->get_size(), nullptr) !=
      HANDTRACK_OK) {
    prev.region.reset();
    return prev;
  }
  prev.valid = true;
  const auto* h = static_cast<const shm::Header*>(prev.region->get_address());
  prev.epoch = h->epoch;
  prev.pid = h->writer_pid;
  // SYNC: relaxed loads: a liveness estimate, guarding no data.
  const auto state = static_cast<DeviceState>(h->device_state.load(std::memory_order_relaxed));
  const std::int64_t age = detail::heartbeat_age_ns(
      detail::monotonic_ns(), h->heartbeat_ns.load(std::memory_order_relaxed));
  const bool fresh = age <= detail::dead_after_ns(h->heartbeat_period_ns, shm::kDeadAfterHalfPeriods);
  prev.live = state != DeviceState::kStopped && fresh && pid_exists(prev.pid);
  return prev;
}

}  // namespace

PoseRingWriter::PoseRingWriter(const Options& options)
    : name_(options.name),
      capacity_(options.capacity),
      heartbeat_period_(options.heartbeat_period),
      test_hook_mid_publish_(options.test_hook_mid_publish) {
  if (name_.empty() || name_.size() > 200 || name_.find('/') != std::string::npos) {
    fail(name_, "invalid name (1..200 characters, no '/')");
  }
  if (capacity_ < 2 || capacity_ > shm::kMaxCapacity) {
    fail(name_, "capacity " + std::to_string(capacity_) + " outside 2.." +
                    std::to_string(shm::kMaxCapacity));
  }
  const std::int64_t period_ns = heartbeat_period_.count();
  if (period_ns < shm::kMinHeartbeatPeriodNs || period_ns > shm::kMaxHeartbeatPeriodNs) {
    fail(name_, "heartbeat period " + std::to_string(period_ns) + " ns outside 1 ms..1 h");
  }
  if ((options.mode & ~0777U) != 0) fail(name_, "mode must be a permission mask like 0640");
  if ((options.mode & 022U) != 0) fail(name_, "mode must not let other users write (readers refuse such a segment)");

  Previous prev = inspect_previous(name_);
  if (prev.live && !options.replace_live_writer) {
    fail(name_, "in use by a live writer (pid " + std::to_string(prev.pid) + ", epoch " +
                    std::to_string(prev.epoch) + ")");
  }
  if (prev.exists && ::shm_unlink(("/" + name_).c_str()) != 0 && errno != ENOENT) {
    const int err = errno;
    if (err == EPERM || err == EACCES) {
      const std::string who = prev.foreign_owner ? detail::describe_user(*prev.foreign_owner) : "another user";
      fail(name_, "the name is taken by an object of " + who +
                      " that this user may not remove; remove it as root (rm /dev/shm/" + name_ +
                      ") or choose another name");
    }
    fail(name_, std::string("cannot remove the stale segment: ") + std::strerror(err));
  }
  if (prev.foreign_owner) removed_foreign_owner_ = detail::describe_user(*prev.foreign_owner);
  if (prev.valid) replaced_epoch_ = prev.epoch;

  const std::uint64_t total = shm::segment_size(capacity_);
  mapping_ = std::make_unique<Mapping>();
  try {
    mapping_->object = bip::shared_memory_object(bip::create_only, name_.c_str(), bip::read_write,
                                                 bip::permissions(options.mode));
  } catch (const bip::interprocess_exception& e) {
    fail(name_, std::string("cannot create: ") + e.what());
  }
  const int fd = mapping_->object.get_mapping_handle().handle;
  // Boost already fchmod()s after creating (so the umask does not narrow the mode); do it again
  // so the mode is right whatever the Boost version.
  if (::fchmod(fd, static_cast<mode_t>(options.mode)) != 0) {
    const int err = errno;
    remove(name_);
    fail(name_, std::string("cannot set mode: ") + std::strerror(err));
  }
  // Reserve every page now: on tmpfs a plain ftruncate() only sets the size, and a full /dev/shm
  // would surface as SIGBUS on the first store to an unbacked page, in the middle of streaming.
  if (const int err = ::posix_fallocate(fd, 0, static_cast<off_t>(total)); err != 0) {
    remove(name_);
    fail(name_, "cannot reserve " + std::to_string(total) + " bytes (" + std::strerror(err) +
                    "; is /dev/shm full?)");
  }
  try {
    mapping_->region = bip::mapped_region(mapping_->object, bip::read_write, 0, total);
  } catch (const bip::interprocess_exception& e) {
    remove(name_);
    fail(name_, std::string("cannot map: ") + e.what());
  }

  void* base = mapping_->region.get_address();
  header_ = new (base) shm::Header();  // value-initialized: every field and atomic 0
  slots_ = reinterpret_cast<shm::Slot*>(static_cast<unsigned char*>(base) + sizeof(shm::Header));
  for (std::uint32_t i = 0; i < capacity_; ++i) new (&slots_[i]) shm::Slot();

  // Epoch: greater than the replaced segment's, and at least the wall clock in microseconds so it
  // still grows when the name was removed in between (e.g. across a reboot).
  epoch_ = std::max<std::uint64_t>(prev.valid ? prev.epoch + 1 : 1,
                                   static_cast<std::uint64_t>(detail::realtime_us()));
  header_->abi_version = kAbiVersion;
  header_->endian_marker = shm::kEndianMarker;
  header_->header_size = sizeof(shm::Header);
  header_->record_size = sizeof(FrameRecord);
  header_->slot_size = sizeof(shm::Slot);
  header_->capacity = capacity_;
  header_->total_size = total;
  header_->epoch = epoch_;
  header_->heartbeat_period_ns = period_ns;
  header_->writer_pid = static_cast<std::int32_t>(::getpid());
  // SYNC: relaxed; published together with the identity fields by the magic's release store.
  header_->heartbeat_ns.store(detail::monotonic_ns(), std::memory_order_relaxed);
  header_->device_state.store(static_cast<std::uint32_t>(DeviceState::kStarting),
                              std::memory_order_relaxed);
  // SYNC: release; pairs with validate_segment's acquire load of the magic: a reader that sees
  // the magic sees every identity field above and the zeroed slots.
  header_->magic.store(shm::kMagic, std::memory_order_release);

  if (prev.region) {
    // Tell the old segment's readers to reattach now instead of after its heartbeat goes stale.
    auto* old = static_cast<shm::Header*>(prev.region->get_address());
    // SYNC: relaxed; made visible to waiting readers by the release RMW below (they load the
    // futex word with acquire before looking at `superseded`).
    old->superseded.store(1, std::memory_order_relaxed);
    old->futex_word.fetch_add(1, std::memory_order_release);
    detail::futex_wake_all(&old->futex_word);
  }
}

PoseRingWriter::~PoseRingWriter() {
  if (header_ != nullptr) mark_stopped();
}

void PoseRingWriter::publish(const FrameRecord& frame) noexcept {
  const std::uint64_t index = next_index_;
  shm::Slot& slot = slots_[index % capacity_];
  const std::int64_t now = detail::monotonic_ns();
  FrameRecord stamped = frame;
  stamped.epoch = epoch_;
  stamped.publish_ns = now;

  detail::seqlock_begin_write(slot.seq, 2 * index + 1);
  detail::seqlock_store_words(slot.words, &stamped, shm::kRecordWords);
  if (test_hook_mid_publish_ != nullptr) test_hook_mid_publish_(index);
  detail::seqlock_end_write(slot.seq, 2 * index + 2);
  next_index_ = index + 1;

  // SYNC: release; pairs with the readers' acquire load of head: a reader that sees head == i+1
  // sees slot (i % capacity) at seq >= 2i+2.
  header_->head.store(index + 1, std::memory_order_release);
  // SYNC: relaxed: compared with the clock only, guards no data.
  header_->heartbeat_ns.store(now, std::memory_order_relaxed);
  // SYNC: release RMW; pairs with the acquire load of the futex word that a waiting reader does
  // before it checks for a record (no lost wake-up: see PoseRingReader::wait).
  header_->futex_word.fetch_add(1, std::memory_order_release);
  detail::futex_wake_all(&header_->futex_word);
}

void PoseRingWriter::heartbeat() noexcept {
  // SYNC: relaxed: compared with the clock only, guards no data.
  header_->heartbeat_ns.store(detail::monotonic_ns(), std::memory_order_relaxed);
}

void PoseRingWriter::set_device_state(DeviceState state) noexcept {
  // SYNC: relaxed store, published to waiters by the release RMW on the futex word.
  header_->device_state.store(static_cast<std::uint32_t>(state), std::memory_order_relaxed);
  header_->futex_word.fetch_add(1, std::memory_order_release);
  detail::futex_wake_all(&header_->futex_word);
}

void PoseRingWriter::set_stats(const RingStats& stats) noexcept {
  const std::uint64_t version = stats_version_++;
  detail::seqlock_begin_write(header_->stats_seq, 2 * version + 1);
  detail::seqlock_store_words(header_->stats_words, &stats, shm::kStatsWords);
  detail::seqlock_end_write(header_->stats_seq, 2 * version + 2);
}

void PoseRingWriter::mark_stopped() noexcept {
  heartbeat();
  set_device_state(DeviceState::kStopped);
}

bool PoseRingWriter::remove(const std::string& name) noexcept {
  return bip::shared_memory_object::remove(name.c_str());
}

}  // namespace handtrack::ipc
