// handtrack/ipc/pose_ring_shm.hpp: PoseRingShm, the plain-data layout of the shared-memory object.
//
// This is data living in shared memory, kept apart from the per-process code acting on it
// (PoseRingWriter, PoseRingReader). No pointers, no constructors that matter, fixed-width fields,
// explicit alignment, native byte order:
//
//   offset 0              Header (256 bytes, 4 cache lines)
//   offset 256            Slot[capacity], 1344 bytes each (21 cache lines, 64-byte aligned)
//   total_size = 256 + capacity * 1344
//
// A slot holds one frame record (FrameRecord: the frame's fields and all its hands). Every slot is
// a seqlock (Boehm 2012, "Can seqlocks get along with programming language memory models?",
// fig. 6/"fences" variant): seq is 0 (never written), 2i+1 (record i being written) or 2i+2 (holds
// record i, i = 0,1,2,... counts records published in this segment), and the record's 167 words
// are std::atomic<uint64_t> accessed with memory_order_relaxed, so concurrent reading and writing
// is race-free in the C++ memory model (and under TSan); the seq values tell a reader whether the
// words it copied belong to one record. One seqlock covers the whole frame, so the hands a reader
// accepts are all of one frame. See docs/IPC.md and src/seqlock.hpp.
#pragma once

#include <handtrack/ipc/pose_record.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>

namespace handtrack::ipc::shm {

// "HTPOSERG" when the first 8 bytes are dumped on a little-endian machine.
inline constexpr std::uint64_t kMagic = 0x475245534F505448ULL;
// Written in native order; reads back as 0x04030201 on a machine of the other byte order.
inline constexpr std::uint32_t kEndianMarker = 0x01020304U;
inline constexpr std::size_t kRecordWords = sizeof(FrameRecord) / sizeof(std::uint64_t);
inline constexpr std::size_t kStatsWords = sizeof(RingStats) / sizeof(std::uint64_t);
// Upper bound a reader accepts, so a corrupt header cannot make it compute huge offsets.
inline constexpr std::uint32_t kMaxCapacity = 1U << 20;
// Heartbeat periods a reader accepts (1 ms .. 1 h).
inline constexpr std::int64_t kMinHeartbeatPeriodNs = 1'000'000;
inline constexpr std::int64_t kMaxHeartbeatPeriodNs = 3'600'000'000'000;
// A reader declares the writer dead once its heartbeat is older than 2.5 periods: a writer that
// died right after a heartbeat is then reported within 3 periods of its death, with half a
// period left for the reader's own scheduling (SPEC: "within 3 heartbeat periods").
inline constexpr std::int64_t kDeadAfterHalfPeriods = 5;

static_assert(std::atomic<std::uint64_t>::is_always_lock_free);
static_assert(std::atomic<std::int64_t>::is_always_lock_free);
static_assert(std::atomic<std::uint32_t>::is_always_lock_free);
static_assert(sizeof(std::atomic<std::uint64_t>) == 8 && alignof(std::atomic<std::uint64_t>) == 8);
static_assert(sizeof(std::atomic<std::uint32_t>) == 4 && alignof(std::atomic<std::uint32_t>) == 4);

struct alignas(64) Slot {
  // SYNC: the seqlock counter; see the file comment and src/seqlock.hpp for the orders.
  std::atomic<std::uint64_t> seq;
  std::atomic<std::uint64_t> words[kRecordWords];
};
static_assert(sizeof(Slot) == 1344 && sizeof(Slot) == 8 + sizeof(FrameRecord));
static_assert(offsetof(Slot, seq) == 0 && offsetof(Slot, words) == 8);
static_assert(std::is_standard_layout_v<Slot>);

struct alignas(64) Header {
  // --- cache line 0: identity. Written once by the writer before it publishes `magic` (release);
  // immutable afterwards, so a reader that loaded `magic` with acquire may read them plainly.
  std::atomic<std::uint64_t> magic;  // 0 while the writer initializes, then kMagic
  std::uint32_t abi_version;         // HANDTRACK_ABI_VERSION
  std::uint32_t endian_marker;       // kEndianMarker
  std::uint32_t header_size;         // sizeof(Header)
  std::uint32_t record_size;         // sizeof(FrameRecord)
  std::uint32_t slot_size;           // sizeof(Slot)
  std::uint32_t capacity;            // number of slots
  std::uint64_t total_size;          // header_size + capacity * slot_size
  std::uint64_t epoch;               // grows with each writer start (see PoseRingWriter)
  std::int64_t heartbeat_period_ns;  // the writer promises a heartbeat at least this often
  std::int32_t writer_pid;
  std::uint32_t reserved0;

  // --- cache line 1: written by the writer on every publish / heartbeat / state change.
  alignas(64) std::atomic<std::uint64_t> head;  // records published (record i is in slot i % capacity)
  std::atomic<std::int64_t> heartbeat_ns;       // CLOCK_MONOTONIC of the last sign of life
  std::atomic<std::uint32_t> futex_word;        // bumped after every publish and state change
  std::atomic<std::uint32_t> device_state;      // DeviceState
  std::atomic<std::uint32_t> superseded;        // 1: a newer writer replaced this segment
  std::uint32_t reserved1;

  // --- cache lines 2-3: live statistics, their own seqlock (same protocol as a slot).
  alignas(64) std::atomic<std::uint64_t> stats_seq;
  std::atomic<std::uint64_t> stats_words[kStatsWords];
};
static_assert(std::is_standard_layout_v<Header>);
static_assert(sizeof(Header) == 256);
static_assert(offsetof(Header, magic) == 0);
static_assert(offsetof(Header, abi_version) == 8);
static_assert(offsetof(Header, endian_marker) == 12);
static_assert(offsetof(Header, header_size) == 16);
static_assert(offsetof(Header, record_size) == 20);
static_assert(offsetof(Header, slot_size) == 24);
static_assert(offsetof(Header, capacity) == 28);
static_assert(offsetof(Header, total_size) == 32);
static_assert(offsetof(Header, epoch) == 40);
static_assert(offsetof(Header, heartbeat_period_ns) == 48);
static_assert(offsetof(Header, writer_pid) == 56);
static_assert(offsetof(Header, head) == 64);
static_assert(offsetof(Header, heartbeat_ns) == 72);
static_assert(offsetof(Header, futex_word) == 80);
static_assert(offsetof(Header, device_state) == 84);
static_assert(offsetof(Header, superseded) == 88);
static_assert(offsetof(Header, stats_seq) == 128);
static_assert(offsetof(Header, stats_words) == 136);

inline constexpr std::uint64_t segment_size(std::uint32_t capacity) {
  return sizeof(Header) + std::uint64_t{capacity} * sizeof(Slot);
}

// Checks that `mapped_size` bytes at `base` (8-byte aligned) hold a complete, initialized segment
// this library can read: magic, byte order, ABI version, header/record/slot sizes, capacity,
// heartbeat period, and that the mapping covers total_size. Returns HANDTRACK_OK or the error;
// `detail` (may be null) gets one sentence naming the field and the values. Reads only inside
// [base, base + mapped_size). Loads `magic` with acquire (SYNC: pairs with the writer's release
// store of `magic` after it wrote the identity fields).
Status validate_segment(const void* base, std::size_t mapped_size, std::string* detail) noexcept;

}  // namespace handtrack::ipc::shm
