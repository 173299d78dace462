// handtrack-eval's scoring of several hands (tools/eval/src/scoring.cpp, issue 14) on hand-made
// frames whose right answer is known: which tracked hand is matched to which ground-truth hand, and
// what each ground-truth hand's misses, wrong sides, identity swaps and the phantoms add up to. And
// the joint errors: each kind of joint's and the 21 joints' mean, over the frames that can be scored.
#include "handtrack/eval/scoring.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace handtrack::eval {
namespace {

using Eigen::Vector3d;

// A hand's five fingertips spread around `centre` (a palm's width across, fingers up).
Fingertips hand_at(const Vector3d& centre) {
  Fingertips tips;
  for (size_t f = 0; f < kNumFingers; ++f) {
    tips[f] = centre + Vector3d(-40.0 + 20.0 * static_cast<double>(f), -80.0, 10.0);
  }
  return tips;
}

// A tracked hand whose fingertips are those of `truth`, each moved by `offset`.
TrackerOutput tracked(const Fingertips& truth, const Vector3d& offset, uint32_t id,
                      Handedness side = Handedness::kRight) {
  TrackerOutput out;
  out.state = TrackingState::kTracking;
  for (size_t f = 0; f < kNumFingers; ++f) out.fingertips[f] = *truth[f] + offset;
  out.hand_id = id;
  out.handedness = side;
  return out;
}

const Fingertips kRight = hand_at({-100, 0, 400});
const Fingertips kLeft = hand_at({100, 0, 420});

TEST(HandMatching, EachTrackedHandGoesToTheGroundTruthHandItIsOn) {
  // Slot order need not be ground-truth order.
  const std::vector<TrackerOutput> out = {tracked(kLeft, {4, 0, 0}, 7), tracked(kRight, {0, 3, 0}, 8)};
  const std::vector<Fingertips> truth = {kRight, kLeft};
  const HandMatch m = match_hands(out, truth);
  EXPECT_EQ(m.truth_of_tracked, (std::vector<int>{1, 0}));
  EXPECT_EQ(m.tracked_of_truth, (std::vector<int>{1, 0}));
  // The distance is that of the fingertip centroids.
  EXPECT_NEAR(*hand_distance_mm(out[0], kLeft), 4.0, 1e-9);
  EXPECT_NEAR(*hand_distance_mm(out[0], kRight), (Vector3d(200, 0, 20) + Vector3d(4, 0, 0)).norm(), 1e-9);
}

TEST(HandMatching, AHandFarFromEveryGroundTruthHandIsAPhantom) {
  const std::vector<Fingertips> truth = {kRight, kLeft};
  const std::vector<TrackerOutput> out = {tracked(kRight, {0, 0, 0}, 1), tracked(kRight, {0, 0, 150}, 2)};
  const HandMatch m = match_hands(out, truth);
  EXPECT_EQ(m.truth_of_tracked, (std::vector<int>{0, -1}));
  EXPECT_EQ(m.tracked_of_truth, (std::vector<int>{0, -1})) << "the left hand is missed";
  // Just inside the radius it is matched.
  const std::vector<TrackerOutput> near = {tracked(kLeft, {0, 0, kHandMatchRadiusMm - 1.0}, 3)};
  EXPECT_EQ(match_hands(near, truth).tracked_of_truth, (std::vector<int>{-1, 0}));
}

TEST(HandMatching, MostPairsFirstThenTheLeastTotalDistance) {
  // Ground truth at x = 0 and x = 80. Tracked hand 0 at 70 (10 from B), hand 1 at 160 (80 from B,
  // beyond reach of A). Nearest-first would give B to hand 0 and leave hand 1 a phantom; the
  // assignment with the most pairs gives A to hand 0 (70) and B to hand 1 (80).
  const Fingertips a = hand_at({0, 0, 400});
  const Fingertips b = hand_at({80, 0, 400});
  const std::vector<Fingertips> truth = {a, b};
  const std::vector<TrackerOutput> out = {tracked(a, {70, 0, 0}, 1), tracked(a, {160, 0, 0}, 2)};
  EXPECT_EQ(match_hands(out, truth).truth_of_tracked, (std::vector<int>{0, 1}));
  // Both pairings possible: the one with the smaller total (20 + 20, not 30 + 30).
  const Fingertips c = hand_at({50, 0, 400});
  const std::vector<Fingertips> close = {a, c};
  const std::vector<TrackerOutput> between = {tracked(a, {20, 0, 0}, 1), tracked(a, {30, 0, 0}, 2)};
  EXPECT_EQ(match_hands(between, close).truth_of_tracked, (std::vector<int>{0, 1}));
  const std::vector<TrackerOutput> reversed = {between[1], between[0]};
  EXPECT_EQ(match_hands(reversed, close).truth_of_tracked, (std::vector<int>{1, 0}));
}

TEST(HandMatching, NoPoseAndNoAnnotationAreNeverMatched) {
  TrackerOutput lost = tracked(kRight, {0, 0, 0}, 1);
  lost.state = TrackingState::kNoHand;
  const std::vector<Fingertips> truth = {kRight, Fingertips{}};
  const std::vector<TrackerOutput> out = {lost, tracked(kRight, {0, 0, 0}, 2)};
  const HandMatch m = match_hands(out, truth);
  EXPECT_EQ(m.truth_of_tracked, (std::vector<int>{-1, 0}));
  EXPECT_EQ(m.tracked_of_truth, (std::vector<int>{1, -1}));
}

// Six frames of a right (hand 0) and a left hand (hand 1), each tracked 3 and 4 mm off:
//   0, 1  both tracked (ids 1 and 2; in frame 1 the slots in the other order)
//   2     the ids swap hands, and the left hand is reported as a right one
//   3     the left hand is missed
//   4     the left hand is back with a new id (3): no swap across the miss; a phantom far away
//   5     the left hand is not annotated, the right tracked alone
TEST(HandsScoring, MissesSidesSwapsAndPhantomsOfAHandMadeSequence) {
  HandsScorer scorer("pair", {Handedness::kRight, Handedness::kLeft});
  const Vector3d r_off(3, 0, 0), l_off(0, 4, 0);
  const auto frame = [&](const std::vector<TrackerOutput>& out, const std::vector<Fingertips>& truth) {
    return scorer.add(out, truth);
  };
  const std::vector<Fingertips> both = {kRight, kLeft};
  frame({tracked(kRight, r_off, 1), tracked(kLeft, l_off, 2, Handedness::kLeft)}, both);
  frame({tracked(kLeft, l_off, 2, Handedness::kLeft), tracked(kRight, r_off, 1)}, both);
  frame({tracked(kRight, r_off, 2), tracked(kLeft, l_off, 1, Handedness::kRight)}, both);
  const HandMatch missed = frame({tracked(kRight, r_off, 2)}, both);
  EXPECT_EQ(missed.tracked_of_truth, (std::vector<int>{0, -1}));
  frame({tracked(kRight, r_off, 2), tracked(kLeft, l_off, 3, Handedness::kLeft), tracked(kLeft, {0, 0, 300}, 4)},
        both);
  frame({tracked(kRight, r_off, 2)}, {kRight, Fingertips{}});
  const SequenceScore s = scorer.finish(0.5);

  ASSERT_EQ(s.hands.size(), 2U);
  const SequenceScore& right = s.hands[0];
  const SequenceScore& left = s.hands[1];
  EXPECT_EQ(right.frames, 6);
  EXPECT_EQ(right.scored, 6);
  EXPECT_EQ(right.without_pose, 0);
  EXPECT_NEAR(right.mean_error_mm, 3.0, 1e-9);
  EXPECT_EQ(right.identity_swaps, 1);  // 1 -> 2 between frames 1 and 2
  EXPECT_EQ(right.hand_correct, 6);
  EXPECT_EQ(left.frames, 6);
  EXPECT_EQ(left.scored, 4);
  EXPECT_EQ(left.without_pose, 1) << "frame 3: a miss";
  EXPECT_NEAR(left.mean_error_mm, 4.0, 1e-9);
  EXPECT_DOUBLE_EQ(left.pct_below[0], 80.0) << "of its 5 annotated frames, the miss is below no threshold";
  EXPECT_EQ(left.identity_swaps, 1) << "2 -> 1 between frames 1 and 2; not 1 -> 3 across the miss";
  EXPECT_EQ(left.hand_known_frames, 4);
  EXPECT_EQ(left.hand_correct, 3);
  EXPECT_EQ(s.identity_swaps, 2);
  EXPECT_EQ(s.phantom_frames, 1);
  EXPECT_EQ(s.phantom_hands, 1);
  // The sequence's frames pool both hands' fingertips: (5 x 3 + 5 x 4) / 10 = 3.5 mm, frame 5 the
  // right hand's 3 mm alone, frame 3 a miss.
  ASSERT_EQ(s.per_frame_error_mm.size(), 6U);
  EXPECT_NEAR(s.per_frame_error_mm[0], 3.5, 1e-9);
  EXPECT_TRUE(std::isinf(s.per_frame_error_mm[3]));
  EXPECT_NEAR(s.per_frame_error_mm[5], 3.0, 1e-9);
  EXPECT_NEAR(s.mean_error_mm, (4 * 3.5 + 3.0) / 5, 1e-9);
  EXPECT_EQ(s.without_pose, 1);
  EXPECT_EQ(s.hand_known_frames, 10);
  EXPECT_EQ(s.hand_correct, 9);

  // JSON: the one-hand keys as before, and the hands beside them; pooled by index overall.
  const SequenceScore total = overall({s, s});
  const nlohmann::json j = to_json({s, s}, total);
  const auto& hands = j.at("sequences").at(0).at("hands");
  ASSERT_EQ(hands.size(), 2U);
  EXPECT_EQ(hands.at(1).at("side"), "left");
  EXPECT_EQ(hands.at(1).at("misses"), 1);
  EXPECT_EQ(hands.at(1).at("identity_swaps"), 1);
  EXPECT_NEAR(hands.at(1).at("identity_swaps_per_1000_frames").get<double>(), 1000.0 / 6, 1e-9);
  EXPECT_DOUBLE_EQ(hands.at(1).at("handedness").at("pct_frames_correct").get<double>(), 75.0);
  EXPECT_EQ(j.at("sequences").at(0).at("phantom_frames"), 1);
  EXPECT_NEAR(j.at("sequences").at(0).at("mean_fingertip_error_mm").get<double>(), 3.4, 1e-9);
  EXPECT_EQ(j.at("overall").at("hands").at(0).at("frames"), 12);
  EXPECT_EQ(j.at("overall").at("hands").at(1).at("identity_swaps"), 2);
  EXPECT_EQ(j.at("overall").at("phantom_hands"), 2);
}

TEST(HandsScoring, OneHandScoresHaveNoHandsInTheirJson) {
  SequenceScorer one("single", Handedness::kRight);
  one.add(tracked(kRight, {2, 0, 0}, 1), kRight);
  const SequenceScore s = one.finish(0.1);
  const nlohmann::json j = to_json({s}, overall({s}));
  EXPECT_FALSE(j.at("sequences").at(0).contains("hands"));
  EXPECT_FALSE(j.at("overall").contains("hands"));
  EXPECT_FALSE(j.at("overall").contains("phantom_frames"));
  EXPECT_EQ(format_table({s}, overall({s})).find("per hand"), std::string::npos);
}

// 21 joints spread over a hand near `centre`, and a tracked hand whose wrist is `wrist_mm` off and
// whose k-th joint of every finger (MCP, PIP, DIP, TIP) is `k_mm[k]` off, each along another axis.
Joints joints_at(const Vector3d& centre) {
  Joints joints;
  for (size_t j = 0; j < joints.size(); ++j) joints[j] = centre + Vector3d(7.0 * j, -5.0 * j, 2.0 * j);
  return joints;
}
TrackerOutput tracked_joints(const Joints& truth, double wrist_mm, const std::array<double, 4>& k_mm) {
  TrackerOutput out;
  out.state = TrackingState::kTracking;
  out.joints = truth;
  out.joints[kWristJoint] += Vector3d(0, 0, wrist_mm);
  for (int f = 0; f < kNumFingers; ++f) {
    for (int k = 0; k < 4; ++k) {
      const Vector3d axis = f % 2 == 0 ? Vector3d::UnitX() : Vector3d::UnitY();
      out.joints[static_cast<size_t>(joint_index(f, k))] += k_mm[static_cast<size_t>(k)] * axis;
    }
  }
  return out;
}

TEST(JointScoring, EachKindIsTheMeanOfItsJointsAndAllTheMeanOfTheTwentyOne) {
  const Joints truth = joints_at({0, 0, 400});
  SequenceScorer scorer("joints", Handedness::kRight);
  scorer.add(tracked_joints(truth, 10.0, {2.0, 4.0, 6.0, 8.0}), kRight, truth);
  // Not scored on their joints: a frame without a pose, one with a NaN pose, one without joints.
  scorer.add(TrackerOutput{}, kRight, truth);
  TrackerOutput nan_pose = tracked_joints(truth, 50.0, {50.0, 50.0, 50.0, 50.0});
  nan_pose.params[3] = std::numeric_limits<double>::quiet_NaN();
  scorer.add(nan_pose, kRight, truth);
  scorer.add(tracked_joints(truth, 50.0, {50.0, 50.0, 50.0, 50.0}), kRight);
  const SequenceScore s = scorer.finish(0.1);
  EXPECT_EQ(s.joints.frames, 1);
  const std::array<double, 5> kinds = {10.0, 2.0, 4.0, 6.0, 8.0};
  for (size_t k = 0; k < kinds.size(); ++k) EXPECT_NEAR(s.joints.kind_mean_mm(k), kinds[k], 1e-9) << kJointKinds[k];
  EXPECT_NEAR(s.joints.mean_mm(), (10.0 + 5 * (2.0 + 4.0 + 6.0 + 8.0)) / 21, 1e-9);

  // Pooled with a sequence without joints.csv, and in the JSON; none scored is null, not 0.
  SequenceScorer other("no joints");
  other.add(tracked_joints(truth, 30.0, {30.0, 30.0, 30.0, 30.0}), kRight);
  const SequenceScore without = other.finish(0.1);
  EXPECT_TRUE(std::isnan(without.joints.mean_mm()));
  const nlohmann::json j = to_json({s, without}, overall({s, without}));
  const auto& all = j.at("overall").at("joints");
  EXPECT_EQ(all.at("frames_scored"), 1);
  EXPECT_NEAR(all.at("mean_error_mm").get<double>(), 110.0 / 21, 1e-9);
  EXPECT_NEAR(all.at("mean_error_by_kind_mm").at("wrist").get<double>(), 10.0, 1e-9);
  EXPECT_NEAR(all.at("mean_error_by_kind_mm").at("tip").get<double>(), 8.0, 1e-9);
  EXPECT_TRUE(j.at("sequences").at(1).at("joints").at("mean_error_mm").is_null());
  EXPECT_NE(format_table({s, without}, overall({s, without})).find("joint error"), std::string::npos);
  EXPECT_EQ(format_table({without}, overall({without})).find("joint error"), std::string::npos)
      << "no joint table where no sequence has joints";
}

TEST(JointScoring, EachGroundTruthHandIsScoredOnTheHandMatchedToIt) {
  const Joints right_joints = joints_at({-100, 0, 400});
  const Joints left_joints = joints_at({100, 0, 420});
  HandsScorer scorer("pair", {Handedness::kRight, Handedness::kLeft});
  // The slots in the other order: the left hand's fit comes first. Then the left hand is missed.
  TrackerOutput right = tracked_joints(right_joints, 4.0, {4.0, 4.0, 4.0, 4.0});
  TrackerOutput left = tracked_joints(left_joints, 12.0, {12.0, 12.0, 12.0, 12.0});
  right.fingertips = tracked(kRight, {0, 0, 0}, 1).fingertips;
  left.fingertips = tracked(kLeft, {0, 0, 0}, 2).fingertips;
  const std::vector<Fingertips> tips = {kRight, kLeft};
  const std::vector<std::optional<Joints>> joints = {right_joints, left_joints};
  scorer.add(std::vector<TrackerOutput>{left, right}, tips, joints);
  scorer.add(std::vector<TrackerOutput>{right}, tips, joints);
  const SequenceScore s = scorer.finish(0.1);
  EXPECT_EQ(s.hands[0].joints.frames, 2);
  EXPECT_NEAR(s.hands[0].joints.mean_mm(), 4.0, 1e-9);
  EXPECT_EQ(s.hands[1].joints.frames, 1) << "a missed hand is not scored on its joints";
  EXPECT_NEAR(s.hands[1].joints.mean_mm(), 12.0, 1e-9);
  EXPECT_EQ(s.joints.frames, 3);
  EXPECT_NEAR(s.joints.mean_mm(), (4.0 + 4.0 + 12.0) / 3, 1e-9);
  // Joints for one hand of two is a caller's mistake.
  EXPECT_THROW(scorer.add(std::vector<TrackerOutput>{right}, tips, std::vector<std::optional<Joints>>{right_joints}),
               std::invalid_argument);
}

}  // namespace
}  // namespace handtrack::eval
