// The core -> ipc seam (daemon/pipeline/pose_record.cpp): every field of a TrackerOutput lands in
// the hand record clients read, at the index clients expect; every tracking state and handedness
// keeps its meaning across the seam; no hand seen is a frame with no hands; two hands are two
// records, each with its own optimize time.
#include "pose_record.hpp"

#include <gtest/gtest.h>

#include <utility>

namespace handtrack::daemon {
namespace {

// A frame with the one hand `hand` whose optimisation took `optimize_ms` (none when its state is
// no hand).
HandsOutput one_hand(const TrackerOutput& hand, double optimize_ms = 1.0) {
  HandsOutput out;
  if (hand.state == TrackingState::kNoHand) return out;
  out.count = 1;
  out.hands[0] = hand;
  out.optimize_ms[0] = optimize_ms;
  return out;
}

TEST(PoseRecordSeam, EveryTrackingStateKeepsItsMeaning) {
  EXPECT_EQ(to_ipc(TrackingState::kNoHand), ipc::TrackingState::kNoHand);
  EXPECT_EQ(to_ipc(TrackingState::kTracking), ipc::TrackingState::kTracking);
  EXPECT_EQ(to_ipc(TrackingState::kRecovering), ipc::TrackingState::kRecovering);
  ipc::FrameRecord r{};
  TrackerOutput o;
  o.state = TrackingState::kRecovering;
  o.hand_id = 3;
  fill_hands(one_hand(o), r);
  ASSERT_EQ(r.hand_count, 1U);
  EXPECT_EQ(r.hands[0].state, HANDTRACK_STATE_RECOVERING);
}

TEST(PoseRecordSeam, EveryHandednessKeepsItsMeaning) {
  EXPECT_EQ(to_ipc(Handedness::kLeft), ipc::Handedness::kLeft);
  EXPECT_EQ(to_ipc(Handedness::kRight), ipc::Handedness::kRight);
  const std::pair<Handedness, int32_t> hands[] = {{Handedness::kLeft, HANDTRACK_HANDEDNESS_LEFT},
                                                  {Handedness::kRight, HANDTRACK_HANDEDNESS_RIGHT}};
  for (const auto& [hand, code] : hands) {
    TrackerOutput o;
    o.state = TrackingState::kTracking;
    o.hand_id = 1;
    o.handedness = hand;
    ipc::FrameRecord r{};
    fill_hands(one_hand(o), r);
    EXPECT_EQ(r.hands[0].handedness, code) << to_string(hand);
  }
}

TEST(PoseRecordSeam, NoHandIsAFrameWithoutHands) {
  ipc::FrameRecord r{};
  TrackerOutput tracked;
  tracked.state = TrackingState::kTracking;
  tracked.hand_id = 4;
  fill_hands(one_hand(tracked), r);  // the record is reused frame after frame
  ASSERT_EQ(r.hand_count, 1U);
  fill_hands(HandsOutput{}, r);
  EXPECT_EQ(r.hand_count, 0U);
  EXPECT_EQ(r.hands[0].hand_id, 0U) << "the lost hand's record is cleared";
  EXPECT_EQ(r.hands[0].state, HANDTRACK_STATE_NO_HAND);
}

TEST(PoseRecordSeam, EveryValueLandsInItsField) {
  TrackerOutput o;
  o.state = TrackingState::kTracking;
  o.hand_id = 7;
  o.handedness = Handedness::kLeft;
  o.handedness_confidence = 0.375;
  for (int i = 0; i < kNumPoseParams; ++i) o.params[i] = 0.001 * i + 1e-12;  // double precision survives
  for (int j = 0; j < kNumJoints; ++j) o.joints[static_cast<size_t>(j)] = {100.0 + j, 200.0 + j, 300.0 + j};
  for (int t = 0; t < kNumFingers; ++t) o.fingertips[static_cast<size_t>(t)] = {-1.0 - t, -2.0 - t, 400.0 + t};
  o.palm_centre = {1, 2, 350};
  o.palm_normal = {0, 0, -1};
  o.energy = -12.5;
  o.confidence = 0.75;
  o.pinch_distance_mm = 21;
  o.pinch_strength = 0.25;
  o.scale = {.length = 1.1, .width = 0.9, .sigma = 1.05};  // its own (self-calibration)
  ipc::FrameRecord r{};
  r.frame = 77;  // the publisher's fields are left alone
  fill_hands(one_hand(o, 2.5), r);
  EXPECT_EQ(r.frame, 77U);
  ASSERT_EQ(r.hand_count, 1U);
  const ipc::HandRecord& h = r.hands[0];
  EXPECT_EQ(h.hand_id, 7U);
  EXPECT_EQ(h.handedness, HANDTRACK_HANDEDNESS_LEFT);
  EXPECT_FLOAT_EQ(h.handedness_confidence, 0.375F);
  EXPECT_EQ(h.state, HANDTRACK_STATE_TRACKING);
  EXPECT_FLOAT_EQ(h.confidence, 0.75F);
  EXPECT_FLOAT_EQ(h.energy, -12.5F);
  EXPECT_FLOAT_EQ(h.optimize_ms, 2.5F);
  for (int i = 0; i < kNumPoseParams; ++i) EXPECT_EQ(h.params[i], o.params[i]) << "param " << i;
  for (int j = 0; j < kNumJoints; ++j) {
    EXPECT_FLOAT_EQ(h.joints_mm[j][0], 100.0F + static_cast<float>(j));
    EXPECT_FLOAT_EQ(h.joints_mm[j][1], 200.0F + static_cast<float>(j));
    EXPECT_FLOAT_EQ(h.joints_mm[j][2], 300.0F + static_cast<float>(j));
  }
  for (int t = 0; t < kNumFingers; ++t) {
    EXPECT_FLOAT_EQ(h.fingertips_mm[t][0], -1.0F - static_cast<float>(t));
    EXPECT_FLOAT_EQ(h.fingertips_mm[t][2], 400.0F + static_cast<float>(t));
  }
  EXPECT_FLOAT_EQ(h.palm_center_mm[2], 350.0F);
  EXPECT_FLOAT_EQ(h.palm_normal[2], -1.0F);
  EXPECT_FLOAT_EQ(h.pinch_distance_mm, 21.0F);
  EXPECT_FLOAT_EQ(h.pinch_strength, 0.25F);
  EXPECT_FLOAT_EQ(h.hand_scale[0], 1.1F);
  EXPECT_FLOAT_EQ(h.hand_scale[1], 0.9F);
  EXPECT_FLOAT_EQ(h.hand_scale[2], 1.05F);
  EXPECT_EQ(h.flags, 0U);
  EXPECT_EQ(r.hands[1].hand_id, 0U) << "one hand tracked: the second record stays empty";
}

TEST(PoseRecordSeam, TwoHandsAreTwoRecordsEachWithItsOwnTimes) {
  HandsOutput out;
  out.count = 2;
  out.hands[0].state = TrackingState::kRecovering;
  out.hands[0].hand_id = 5;
  out.hands[0].handedness = Handedness::kRight;
  out.hands[1].state = TrackingState::kTracking;
  out.hands[1].hand_id = 6;
  out.hands[1].handedness = Handedness::kLeft;
  out.optimize_ms = {1.5, 2.25};
  ipc::FrameRecord r{};
  fill_hands(out, r);
  ASSERT_EQ(r.hand_count, 2U);
  EXPECT_EQ(r.hands[0].hand_id, 5U);
  EXPECT_EQ(r.hands[0].handedness, HANDTRACK_HANDEDNESS_RIGHT);
  EXPECT_FLOAT_EQ(r.hands[0].optimize_ms, 1.5F);
  EXPECT_EQ(r.hands[1].hand_id, 6U);
  EXPECT_EQ(r.hands[1].handedness, HANDTRACK_HANDEDNESS_LEFT);
  EXPECT_FLOAT_EQ(r.hands[1].optimize_ms, 2.25F);
  // The frame's state: tracking when any hand tracks, else recovering, else no hand.
  EXPECT_EQ(frame_state(out), TrackingState::kTracking);
  out.hands[1].state = TrackingState::kRecovering;
  EXPECT_EQ(frame_state(out), TrackingState::kRecovering);
  EXPECT_EQ(frame_state(HandsOutput{}), TrackingState::kNoHand);
}

}  // namespace
}  // namespace handtrack::daemon
