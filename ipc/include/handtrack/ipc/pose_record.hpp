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

using PoseRecord = ::handtrack_pose;            // one pose (640 bytes)
using RingStats = ::handtrack_stats;            // live statistics filled by the daemon
using WriterStatus = ::handtrack_writer_status; // what a reader learns about the writer
using Status = ::handtrack_status;              // reader results: OK, >0 "nothing yet", <0 errors

enum class TrackingState : std::int32_t {
  kNoHand = HANDTRACK_STATE_NO_HAND,
  kTracking = HANDTRACK_STATE_TRACKING,
  kRecovering = HANDTRACK_STATE_RECOVERING,
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

// The records are copied word by word through std::atomic<uint64_t> (see pose_ring_shm.hpp), so
// they must be trivially copyable, padding-free multiples of 8 bytes.
static_assert(std::is_trivially_copyable_v<PoseRecord>);
static_assert(std::is_standard_layout_v<PoseRecord>);
static_assert(sizeof(PoseRecord) == 640 && sizeof(PoseRecord) % 8 == 0);
static_assert(offsetof(PoseRecord, frame) == 0);
static_assert(offsetof(PoseRecord, epoch) == 8);
static_assert(offsetof(PoseRecord, capture_ns) == 16);
static_assert(offsetof(PoseRecord, publish_ns) == 24);
static_assert(offsetof(PoseRecord, grab_ms) == 32);
static_assert(offsetof(PoseRecord, state) == 48);
static_assert(offsetof(PoseRecord, confidence) == 52);
static_assert(offsetof(PoseRecord, energy) == 56);
static_assert(offsetof(PoseRecord, params) == 64);
static_assert(offsetof(PoseRecord, joints_mm) == 272);
static_assert(offsetof(PoseRecord, fingertips_mm) == 524);
static_assert(offsetof(PoseRecord, palm_center_mm) == 584);
static_assert(offsetof(PoseRecord, palm_normal) == 596);
static_assert(offsetof(PoseRecord, pinch_distance_mm) == 608);
static_assert(offsetof(PoseRecord, pinch_strength) == 612);
static_assert(offsetof(PoseRecord, hand_scale) == 616);
static_assert(offsetof(PoseRecord, reserved) == 628);
static_assert(std::is_trivially_copyable_v<RingStats> && sizeof(RingStats) == 64);
static_assert(offsetof(RingStats, frames_captured) == 32);
static_assert(std::is_trivially_copyable_v<WriterStatus> && sizeof(WriterStatus) == 120);
static_assert(offsetof(WriterStatus, stats) == 56);

}  // namespace handtrack::ipc
