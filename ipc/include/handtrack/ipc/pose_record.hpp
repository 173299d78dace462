// handtrack/ipc/pose_record.hpp: the C++ names of the records that travel through shared memory.
//
// The record types ARE the C API's structs (handtrack/client.h): one layout, one definition, so a
// record read by the C library, the C++ reader or Python is byte-for-byte what the writer wrote.
#pragma once

#include <handtrack/client.h>

#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace handtrack::ipc {

using FrameRecord = ::handtrack_frame;          // one frame: every hand of it (1336 bytes)
using HandRecord = ::handtrack_hand;            // one hand of a frame (640 bytes)
using RingStats = ::handtrack_stats;            // live statistics filled by the daemon
using WriterStatus = ::handtrack_writer_status; // what a reader learns about the writer
using Status = ::handtrack_status;              // reader results: OK, >0 "nothing yet", <0 errors

enum class TrackingState : std::int32_t {
  kNoHand = HANDTRACK_STATE_NO_HAND,
  kTracking = HANDTRACK_STATE_TRACKING,
  kRecovering = HANDTRACK_STATE_RECOVERING,
};

enum class Handedness : std::int32_t {
  kUnknown = HANDTRACK_HANDEDNESS_UNKNOWN,
  kLeft = HANDTRACK_HANDEDNESS_LEFT,
  kRight = HANDTRACK_HANDEDNESS_RIGHT,
};

enum class DeviceState : std::uint32_t {
  kStopped = HANDTRACK_DEVICE_STOPPED,
  kStarting = HANDTRACK_DEVICE_STARTING,
  kWaitingForDevice = HANDTRACK_DEVICE_WAITING_FOR_DEVICE,
  kStreaming = HANDTRACK_DEVICE_STREAMING,
  kError = HANDTRACK_DEVICE_ERROR,
};

inline constexpr std::uint32_t kAbiVersion = HANDTRACK_ABI_VERSION;
inline constexpr const char* kDefaultShmName = HANDTRACK_DEFAULT_SHM_NAME;
inline constexpr std::uint32_t kMaxHands = HANDTRACK_MAX_HANDS;

// The records are copied word by word through std::atomic<uint64_t> (see pose_ring_shm.hpp), so
// they must be trivially copyable, padding-free multiples of 8 bytes.
// A frame record is copied as a whole under one slot's seqlock: every hand of a frame is read
// together with the frame's fields, never hands of two frames mixed (docs/IPC.md).
static_assert(std::is_trivially_copyable_v<HandRecord>);
static_assert(std::is_standard_layout_v<HandRecord>);
static_assert(sizeof(HandRecord) == 640 && alignof(HandRecord) == 8);
static_assert(offsetof(HandRecord, hand_id) == 0);
static_assert(offsetof(HandRecord, handedness) == 4);
static_assert(offsetof(HandRecord, handedness_confidence) == 8);
static_assert(offsetof(HandRecord, state) == 12);
static_assert(offsetof(HandRecord, confidence) == 16);
static_assert(offsetof(HandRecord, energy) == 20);
static_assert(offsetof(HandRecord, optimize_ms) == 24);
static_assert(offsetof(HandRecord, flags) == 28);
static_assert(offsetof(HandRecord, params) == 32);
static_assert(offsetof(HandRecord, joints_mm) == 240);
static_assert(offsetof(HandRecord, fingertips_mm) == 492);
static_assert(offsetof(HandRecord, palm_center_mm) == 552);
static_assert(offsetof(HandRecord, palm_normal) == 564);
static_assert(offsetof(HandRecord, pinch_distance_mm) == 576);
static_assert(offsetof(HandRecord, pinch_strength) == 580);
static_assert(offsetof(HandRecord, hand_scale) == 584);
static_assert(offsetof(HandRecord, reserved) == 596);

static_assert(std::is_trivially_copyable_v<FrameRecord>);
static_assert(std::is_standard_layout_v<FrameRecord>);
static_assert(sizeof(FrameRecord) == 1336 && sizeof(FrameRecord) % 8 == 0);
static_assert(offsetof(FrameRecord, frame) == 0);
static_assert(offsetof(FrameRecord, epoch) == 8);
static_assert(offsetof(FrameRecord, capture_ns) == 16);
static_assert(offsetof(FrameRecord, publish_ns) == 24);
static_assert(offsetof(FrameRecord, grab_ms) == 32);
static_assert(offsetof(FrameRecord, preprocess_ms) == 36);
static_assert(offsetof(FrameRecord, optimize_ms) == 40);
static_assert(offsetof(FrameRecord, publish_ms) == 44);
static_assert(offsetof(FrameRecord, hand_count) == 48);
static_assert(offsetof(FrameRecord, flags) == 52);
static_assert(offsetof(FrameRecord, hands) == 56 && std::extent_v<decltype(FrameRecord::hands)> == kMaxHands);
static_assert(offsetof(FrameRecord, hands[1]) == 56 + sizeof(HandRecord));
static_assert(std::is_trivially_copyable_v<RingStats> && sizeof(RingStats) == 64);
static_assert(offsetof(RingStats, frames_captured) == 32);
static_assert(std::is_trivially_copyable_v<WriterStatus> && sizeof(WriterStatus) == 120);
static_assert(offsetof(WriterStatus, stats) == 56);

}  // namespace handtrack::ipc
