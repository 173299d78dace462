// Test frames whose every field is a function of the frame number: the frame's own fields and
// HANDTRACK_MAX_HANDS hands, hand k built from (frame, k) with the frame number itself in its
// params[0], plus a checksum of the whole record in the last hand's params[25]. A reader can tell
// a torn record (words of two records) from a whole one, and a frame whose hands belong to
// different frames (hands_of_one_frame) from one whose hands are all its own.
// tests/ipc/test_python.py re-implements make_test_record; keep the two in step.
#pragma once

#include <handtrack/ipc/pose_record.hpp>

#include <cstdint>
#include <cstring>

namespace handtrack::ipc::test {

// Where the checksum lives: a double holds a 32-bit value exactly.
inline double& checksum_field(FrameRecord& record) { return record.hands[kMaxHands - 1].params[25]; }
inline double checksum_field(const FrameRecord& record) { return record.hands[kMaxHands - 1].params[25]; }

// FNV-1a (32 bit) over the record with the fields the writer stamps (epoch, publish_ns) and the
// checksum itself zeroed.
inline std::uint32_t record_checksum(const FrameRecord& record) {
  FrameRecord copy = record;
  copy.epoch = 0;
  copy.publish_ns = 0;
  checksum_field(copy) = 0.0;
  unsigned char bytes[sizeof copy];
  std::memcpy(bytes, &copy, sizeof copy);
  std::uint32_t hash = 2166136261U;
  for (unsigned char b : bytes) {
    hash ^= b;
    hash *= 16777619U;
  }
  return hash;
}

// Hand k of test frame `frame`.
inline HandRecord make_test_hand(std::uint64_t frame, std::uint32_t k) {
  HandRecord h{};
  const auto kf = static_cast<float>(k);
  const auto f = static_cast<float>(frame % 1000);
  h.hand_id = k + 1;  // stable: the same two hands in every frame
  h.handedness = k == 0 ? HANDTRACK_HANDEDNESS_RIGHT : HANDTRACK_HANDEDNESS_LEFT;
  h.handedness_confidence = static_cast<float>(frame % 64) / 64.0F;
  h.state = static_cast<std::int32_t>(1 + (frame + k) % 2);  // tracking, recovering
  h.confidence = static_cast<float>(frame % 100) / 128.0F + kf / 1024.0F;
  h.energy = f * 0.5F + kf;
  h.optimize_ms = f * 0.25F + 2.0F + kf;
  h.params[0] = static_cast<double>(frame);  // hands_of_one_frame reads it back
  for (int i = 1; i < 26; ++i) h.params[i] = static_cast<double>(frame) + i * 0.5 + k * 1000.0;
  const auto base = static_cast<float>(frame % 4096) + 500.0F * kf;
  for (int j = 0; j < HANDTRACK_NUM_JOINTS; ++j) {
    for (int a = 0; a < 3; ++a) h.joints_mm[j][a] = base + static_cast<float>(j * 3 + a);
  }
  for (int t = 0; t < HANDTRACK_NUM_FINGERTIPS; ++t) {
    for (int a = 0; a < 3; ++a) h.fingertips_mm[t][a] = base + 100.0F + static_cast<float>(t * 3 + a);
  }
  for (int a = 0; a < 3; ++a) h.palm_center_mm[a] = base + 200.0F + static_cast<float>(a);
  h.palm_normal[0] = 0.0F;
  h.palm_normal[1] = 0.0F;
  h.palm_normal[2] = k == 0 ? -1.0F : 1.0F;
  h.pinch_distance_mm = static_cast<float>(frame % 256) * 0.5F + kf;
  h.pinch_strength = static_cast<float>((frame + k) % 4) * 0.25F;
  h.hand_scale[0] = 1.0F + static_cast<float>(frame % 8) * 0.125F;
  h.hand_scale[1] = 1.25F + 0.125F * kf;
  h.hand_scale[2] = 0.75F;
  return h;
}

inline FrameRecord make_test_record(std::uint64_t frame) {
  FrameRecord r{};
  r.frame = frame;
  r.capture_ns = static_cast<std::int64_t>(frame * 1000 + 7);
  const auto f = static_cast<float>(frame % 1000);
  r.grab_ms = f * 0.25F;
  r.preprocess_ms = r.grab_ms + 1.0F;
  r.optimize_ms = r.grab_ms + 2.0F;
  r.publish_ms = r.grab_ms + 3.0F;
  r.hand_count = kMaxHands;
  for (std::uint32_t k = 0; k < kMaxHands; ++k) r.hands[k] = make_test_hand(frame, k);
  checksum_field(r) = static_cast<double>(record_checksum(r));
  return r;
}

// True if `r` is exactly the record make_test_record(r.frame) (apart from the stamped fields)
// and its checksum matches.
inline bool is_whole_test_record(const FrameRecord& r) {
  if (checksum_field(r) != static_cast<double>(record_checksum(r))) return false;
  FrameRecord expected = make_test_record(r.frame);
  expected.epoch = r.epoch;
  expected.publish_ns = r.publish_ns;
  return std::memcmp(&expected, &r, sizeof r) == 0;
}

// True if every hand of `r` carries r's frame number: no hand of another frame got in.
inline bool hands_of_one_frame(const FrameRecord& r) {
  for (std::uint32_t k = 0; k < r.hand_count && k < kMaxHands; ++k) {
    if (r.hands[k].params[0] != static_cast<double>(r.frame)) return false;
  }
  return true;
}

}  // namespace handtrack::ipc::test
