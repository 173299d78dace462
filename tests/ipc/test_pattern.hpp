// Test records whose every field is a function of the frame number, plus a checksum in
// params[25], so a reader can tell a torn record (words of two records) from a whole one.
// tests/ipc/test_python.py re-implements make_test_record; keep the two in step.
#pragma once

#include <handtrack/ipc/pose_record.hpp>

#include <cstdint>
#include <cstring>

namespace handtrack::ipc::test {

// FNV-1a (32 bit) over the record with the fields the writer stamps (epoch, publish_ns) and the
// checksum itself (params[25]) zeroed. A 32-bit value is exact in a double.
inline std::uint32_t record_checksum(const PoseRecord& record) {
  PoseRecord copy = record;
  copy.epoch = 0;
  copy.publish_ns = 0;
  copy.params[25] = 0.0;
  unsigned char bytes[sizeof copy];
  std::memcpy(bytes, &copy, sizeof copy);
  std::uint32_t hash = 2166136261U;
  for (unsigned char b : bytes) {
    hash ^= b;
    hash *= 16777619U;
  }
  return hash;
}

inline PoseRecord make_test_record(std::uint64_t frame) {
  PoseRecord r{};
  r.frame = frame;
  r.capture_ns = static_cast<std::int64_t>(frame * 1000 + 7);
  const auto f = static_cast<float>(frame % 1000);
  r.grab_ms = f * 0.25F;
  r.preprocess_ms = r.grab_ms + 1.0F;
  r.optimize_ms = r.grab_ms + 2.0F;
  r.publish_ms = r.grab_ms + 3.0F;
  r.state = static_cast<std::int32_t>(frame % 3);
  r.confidence = static_cast<float>(frame % 100) / 128.0F;
  r.energy = f * 0.5F;
  for (int k = 0; k < 25; ++k) r.params[k] = static_cast<double>(frame) + k * 0.5;
  const auto base = static_cast<float>(frame % 4096);
  for (int j = 0; j < HANDTRACK_NUM_JOINTS; ++j) {
    for (int a = 0; a < 3; ++a) r.joints_mm[j][a] = base + static_cast<float>(j * 3 + a);
  }
  for (int t = 0; t < HANDTRACK_NUM_FINGERTIPS; ++t) {
    for (int a = 0; a < 3; ++a) r.fingertips_mm[t][a] = base + 100.0F + static_cast<float>(t * 3 + a);
  }
  for (int a = 0; a < 3; ++a) r.palm_center_mm[a] = base + 200.0F + static_cast<float>(a);
  r.palm_normal[0] = 0.0F;
  r.palm_normal[1] = 0.0F;
  r.palm_normal[2] = -1.0F;
  r.pinch_distance_mm = static_cast<float>(frame % 256) * 0.5F;
  r.pinch_strength = static_cast<float>(frame % 4) * 0.25F;
  r.hand_scale[0] = 1.0F + static_cast<float>(frame % 8) * 0.125F;
  r.hand_scale[1] = 1.25F;
  r.hand_scale[2] = 0.75F;
  r.params[25] = static_cast<double>(record_checksum(r));
  return r;
}

// True if `r` is exactly the record make_test_record(r.frame) (apart from the stamped fields)
// and its checksum matches.
inline bool is_whole_test_record(const PoseRecord& r) {
  if (r.params[25] != static_cast<double>(record_checksum(r))) return false;
  PoseRecord expected = make_test_record(r.frame);
  expected.epoch = r.epoch;
  expected.publish_ns = r.publish_ns;
  return std::memcmp(&expected, &r, sizeof r) == 0;
}

}  // namespace handtrack::ipc::test
