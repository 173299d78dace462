// The core -> ipc seam (daemon/pipeline/pose_record.cpp): every field of a TrackerOutput lands in
// the PoseRecord clients read, at the index clients expect, and every tracking state keeps its
// meaning across the seam.
#include "pose_record.hpp"

#include <gtest/gtest.h>

namespace handtrack::daemon {
namespace {

TEST(PoseRecordSeam, EveryTrackingStateKeepsItsMeaning) {
  EXPECT_EQ(to_ipc(TrackingState::kNoHand), ipc::TrackingState::kNoHand);
  EXPECT_EQ(to_ipc(TrackingState::kTracking), ipc::TrackingState::kTracking);
  EXPECT_EQ(to_ipc(TrackingState::kRecovering), ipc::TrackingState::kRecovering);
  ipc::PoseRecord r{};
  TrackerOutput o;
  o.state = TrackingState::kRecovering;
  fill_pose(o, HandScale{}, r);
  EXPECT_EQ(r.state, HANDTRACK_STATE_RECOVERING);
}

TEST(PoseRecordSeam, EveryValueLandsInItsField) {
  TrackerOutput o;
  o.state = TrackingState::kTracking;
  for (int i = 0; i < kNumPoseParams; ++i) o.params[i] = 0.001 * i + 1e-12;  // double precision survives
  for (int j = 0; j < kNumJoints; ++j) o.joints[static_cast<size_t>(j)] = {100.0 + j, 200.0 + j, 300.0 + j};
  for (int t = 0; t < kNumFingers; ++t) o.fingertips[static_cast<size_t>(t)] = {-1.0 - t, -2.0 - t, 400.0 + t};
  o.palm_centre = {1, 2, 350};
  o.palm_normal = {0, 0, -1};
  o.energy = -12.5;
  o.confidence = 0.75;
  o.pinch_distance_mm = 21;
  o.pinch_strength = 0.25;
  const HandScale scale{.length = 1.1, .width = 0.9, .sigma = 1.05};
  ipc::PoseRecord r{};
  r.frame = 77;  // the publisher's fields are left alone
  fill_pose(o, scale, r);
  EXPECT_EQ(r.frame, 77U);
  EXPECT_EQ(r.state, HANDTRACK_STATE_TRACKING);
  EXPECT_FLOAT_EQ(r.confidence, 0.75F);
  EXPECT_FLOAT_EQ(r.energy, -12.5F);
  for (int i = 0; i < kNumPoseParams; ++i) EXPECT_EQ(r.params[i], o.params[i]) << "param " << i;
  for (int j = 0; j < kNumJoints; ++j) {
    EXPECT_FLOAT_EQ(r.joints_mm[j][0], 100.0F + static_cast<float>(j));
    EXPECT_FLOAT_EQ(r.joints_mm[j][1], 200.0F + static_cast<float>(j));
    EXPECT_FLOAT_EQ(r.joints_mm[j][2], 300.0F + static_cast<float>(j));
  }
  for (int t = 0; t < kNumFingers; ++t) {
    EXPECT_FLOAT_EQ(r.fingertips_mm[t][0], -1.0F - static_cast<float>(t));
    EXPECT_FLOAT_EQ(r.fingertips_mm[t][2], 400.0F + static_cast<float>(t));
  }
  EXPECT_FLOAT_EQ(r.palm_center_mm[2], 350.0F);
  EXPECT_FLOAT_EQ(r.palm_normal[2], -1.0F);
  EXPECT_FLOAT_EQ(r.pinch_distance_mm, 21.0F);
  EXPECT_FLOAT_EQ(r.pinch_strength, 0.25F);
  EXPECT_FLOAT_EQ(r.hand_scale[0], 1.1F);
  EXPECT_FLOAT_EQ(r.hand_scale[1], 0.9F);
  EXPECT_FLOAT_EQ(r.hand_scale[2], 1.05F);
  EXPECT_EQ(r.flags, 0U);
}

}  // namespace
}  // namespace handtrack::daemon
