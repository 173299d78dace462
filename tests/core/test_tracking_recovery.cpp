// Recovery (issue 4): frames without a hand say so and carry no pose, a hand that comes back is
// tracked again, and a gross error is repaired within half a second.
#include "synthetic_tracking.hpp"

#include "handtrack/core/kinematics.hpp"
#include "handtrack/eval/scoring.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <string_view>

namespace handtrack {
namespace {

using testing::kSequenceFrames;

// Recovery: the knocked-off tracker is knocked off after each of these frames (slow and fast half).
constexpr std::array<int, 3> kKnockFrames = {60, 140, 220};
constexpr double kKnockRotationRad = 1.6;
// "Back under 20 mm within 30 frames" (issue 4): half a second at the synthetic camera's 60 fps.
// Where the tracker that was not knocked off is itself above 20 mm (the fists of fingercount's
// first 100 frames and of flexex1: the limit of our model, docs/TRACKER.md), "back" means as
// close as that tracker, within kBackAsCloseMm.
constexpr int kRecoveryFrames = 30;
constexpr double kRecoveredMm = 20.0;
constexpr double kBackAsCloseMm = 2.0;

// The gross error: the hand turned by 1.6 rad about a random axis through the wrist, and every
// joint angle drawn uniformly within its limits.
PoseParams knocked_off(const PoseParams& pose, const HandModel& model, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  const Eigen::Vector3d axis = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
  PoseParams out = pose;
  out.segment<3>(kRotationParam) =
      rotation_log(rotation_exp(kKnockRotationRad * axis) * rotation_exp(pose.segment<3>(kRotationParam)));
  for (int j = 0; j < kNumJointAngles; ++j) {
    const auto& limit = model.limits()[static_cast<size_t>(j)];
    out[kFirstAngleParam + j] = std::uniform_real_distribution<double>(limit.lo, limit.hi)(rng);
  }
  return out;
}

// Frames from each knock until the knocked-off tracker is back (-1: not within kRecoveryFrames).
std::vector<int> frames_to_recover(const std::vector<double>& knocked_mm, const std::vector<double>& undisturbed_mm) {
  std::vector<int> out;
  for (const int knock : kKnockFrames) {
    int back = -1;
    for (int i = knock + 1; i <= knock + kRecoveryFrames && back < 0; ++i) {
      const auto k = static_cast<size_t>(i);
      if (knocked_mm[k] < kRecoveredMm || knocked_mm[k] <= undisturbed_mm[k] + kBackAsCloseMm) back = i - knock;
    }
    out.push_back(back);
  }
  return out;
}

// Tracks `motion` with `config` twice on the same frames, once knocked off after each of
// kKnockFrames; `watch` sees every frame's output of the knocked-off tracker. With background
// checks each frame waits for the check under way, as if the camera were slower than the search
// (the same every run). Returns the frames from each knock until it is back (frames_to_recover),
// printed as well.
std::vector<int> knock_off_and_track(std::string_view motion, const TrackerConfig& config, const PartForest& forest,
                                     std::mt19937_64& rng,
                                     const std::function<void(int, const TrackerOutput&, const Tracker&)>& watch = {},
                                     uint64_t seed = testing::kSubjectSeeds[0]) {
  auto camera = testing::motion_camera(motion, seed);
  Tracker undisturbed(config);
  Tracker knocked(config);
  std::vector<double> undisturbed_mm;
  std::vector<double> knocked_mm;
  synth::SynthFrame frame;
  for (int i = 0; i < kSequenceFrames; ++i) {
    camera.render(i, frame);
    undisturbed_mm.push_back(eval::fingertip_error_mm(undisturbed.track(frame.depth, &forest), frame.fingertips));
    const auto out = knocked.track(frame.depth, &forest);
    knocked_mm.push_back(eval::fingertip_error_mm(out, frame.fingertips));
    undisturbed.wait_for_checks();
    knocked.wait_for_checks();
    if (watch) watch(i, out, knocked);
    if (std::find(kKnockFrames.begin(), kKnockFrames.end(), i) != kKnockFrames.end()) {
      auto& pose = knocked.pose_tracker();
      pose.override_pose(knocked_off(out.params, pose.model(), rng));
    }
  }
  const auto recovered = frames_to_recover(knocked_mm, undisturbed_mm);
  for (size_t n = 0; n < recovered.size(); ++n) {
    std::printf("%-12s s%d knocked off after frame %3d: back after %d frames\n", std::string(motion).c_str(),
                static_cast<int>(seed), kKnockFrames[n], recovered[n]);
  }
  return recovered;
}

// Tracks every motion of every subject with late fusion twice on the same frames, once knocked
// off after each of kKnockFrames: of the 63 knocks at least 95 % must be back within 30 frames.
// Measured on the first subject when the check came: all 21 knocks repaired, 20 within 2 frames
// (docs/TRACKER.md, "Recovery"; before the check, 14 of 21). Over three subjects (2026-11-26): 62 of
// 63 back (not: random of subject 9 knocked off after frame 140).
constexpr int kMostKnocksNotBack = 3;

TEST(TrackingRecovery, BackWithin30FramesAfterAGrossError) {
  const PartForest& forest = testing::shipped_forest();
  std::mt19937_64 rng(4);
  int not_back = 0;
  for (const uint64_t seed : testing::kSubjectSeeds) {
    for (const auto motion : synth::kMotionNames) {
      const auto recovered =
          knock_off_and_track(motion, testing::paper_config(EnergyMode::kLateFusion), forest, rng, {}, seed);
      not_back += static_cast<int>(std::count(recovered.begin(), recovered.end(), -1));
    }
  }
  EXPECT_LE(not_back, kMostKnocksNotBack) << "knocks not back within 30 frames, of "
                                          << testing::kSubjectSeeds.size() * synth::kMotionNames.size() * kKnockFrames.size();
}

// Rechecks of a mediocre fit (TrackerConfig::recheck_interval_frames: every 30 frames below a
// confidence of 0.8): a wrong pose whose confidence never fell past the suspect ratio is still
// checked while it explains little of the hand. With the suspect check off, the knocks above are
// found only by the rechecks (and the lost rule): every knock back within 30 frames. The same
// knocks without rechecks show the scenario needs them: then some knock is not back (the lost rule
// alone: docs/TRACKER.md, "Recovery"). Measured: with rechecks 6 of 6 back after 2-3 frames,
// without 2 of 6. (flexex1 is left out: a check shortly before its knock at frame 60 made the
// recheck wait 24 frames, by design up to 30.)
TEST(TrackingRecovery, AMediocreFitIsRecheckedThoughItsConfidenceNeverFell) {
  const PartForest& forest = testing::shipped_forest();
  TrackerConfig config = testing::paper_config(EnergyMode::kLateFusion);
  config.suspect_confidence_ratio = 0.0;
  config.recheck_interval_frames = 30;
  TrackerConfig without = config;
  without.recheck_interval_frames = 0;
  int back_without = 0;
  int knocks = 0;
  for (const auto motion : {"fingerwave", "tigergrasp"}) {
    std::mt19937_64 rng(6);
    std::mt19937_64 same_rng(6);
    const auto recovered = knock_off_and_track(motion, config, forest, rng);
    const auto recovered_without = knock_off_and_track(motion, without, forest, same_rng);
    for (size_t n = 0; n < recovered.size(); ++n) {
      EXPECT_GE(recovered[n], 1) << motion << " knocked off after frame " << kKnockFrames[n]
                                 << " is not back within 30 frames with rechecks";
      back_without += recovered_without[n] >= 1 ? 1 : 0;
      ++knocks;
    }
  }
  EXPECT_LT(back_without, knocks) << "every knock is back without rechecks: the scenario no longer needs them";
}

// The one-hand motions of the latency settings' tests (checks spread over frames, in the
// background), each knocked off as above after kKnockFrames with one random stream.
constexpr std::array<std::string_view, 3> kLatencyMotions = {"random", "flexex1", "fingercount"};

// Tracks kLatencyMotions with `config`; `watch` sees each frame's output, whether the frame before
// was tracked, and whether this frame's hand was segmented afresh though it was (the tracker asked
// for no hint: a check's first frame). Returns the knocks back within kRecoveryFrames.
int latency_knocks_back(const TrackerConfig& config, const PartForest& forest,
                        const std::function<void(std::string_view motion, int frame, const TrackerOutput& out,
                                                 bool after_tracked, bool segmented_afresh)>& watch) {
  int knocks_back = 0;
  std::mt19937_64 rng(5);
  for (const auto motion : kLatencyMotions) {
    TrackingState last_state = TrackingState::kNoHand;
    bool afresh = false;
    const auto recovered =
        knock_off_and_track(motion, config, forest, rng, [&](int i, const TrackerOutput& out, const Tracker& tracker) {
          watch(motion, i, out, last_state == TrackingState::kTracking, afresh);
          last_state = out.state;
          afresh = out.state == TrackingState::kTracking && !tracker.request().right_hint;
        });
    knocks_back += static_cast<int>(std::count_if(recovered.begin(), recovered.end(), [](int f) { return f >= 1; }));
  }
  return knocks_back;
}

// Checks spread over frames (TrackerConfig::check_iterations_per_frame, the latency setting): a
// frame that follows a tracked frame runs tracking's particles and at most about
// check_iterations_per_frame more, never a whole (re)start search; only a frame with no pose to go
// on (the start, a lost fit) searches at once. One hand's tracker (handedness fixed): in auto
// handedness an unclear choice of hand is still re-examined at once (docs/TRACKER.md, "Checks
// spread over frames"). A check's first frame, whose hand is segmented afresh (up to three times a
// tracked frame's preprocessing), runs tracking's particles alone: the search starts on the next
// frame. Knocked off as above, the tracker is back within 30 frames after most knocks, not all:
// measured 8 of 9, random's knock after frame 140 (its fast half) is not back
// within 30 frames, where checks made at once have it back after 2 (the test fails with
// check_iterations_per_frame 0: the frames after the knocks stall on whole searches).
TEST(TrackingRecovery, ChecksSpreadOverFramesKeepEveryFrameShortAndStillRepairAGrossError) {
  const PartForest& forest = testing::shipped_forest();
  TrackerConfig config = testing::paper_config(EnergyMode::kLateFusion);
  config.handedness = HandednessMode::kRight;
  config.check_iterations_per_frame = 64;
  const int tracking_iterations = config.particles * config.optimizer.iterations;
  const int most_after_tracked = tracking_iterations + config.check_iterations_per_frame;
  constexpr int kMostKnocksBack = 7;  // of 3 motions x 3 knocks
  std::map<std::string_view, int> checking_frames;
  int first_frames = 0;
  const int knocks_back = latency_knocks_back(config, forest, [&](auto motion, int i, const TrackerOutput& out,
                                                                  bool after_tracked, bool segmented_afresh) {
    if (after_tracked && segmented_afresh) {
      EXPECT_EQ(out.iterations, tracking_iterations) << motion << " frame " << i << ": a check's first frame searched";
      ++first_frames;
    }
    if (i == 0) {
      EXPECT_GT(out.iterations, most_after_tracked) << motion << ": the start searches at once";
    }
    if (after_tracked) {
      EXPECT_LE(out.iterations, most_after_tracked) << motion << " frame " << i << " stalls on a whole search";
      checking_frames[motion] += out.iterations > tracking_iterations ? 1 : 0;
    }
  });
  for (const auto motion : kLatencyMotions) {
    std::printf("%-12s frames with a check under way: %d\n", std::string(motion).c_str(), checking_frames[motion]);
    EXPECT_GT(checking_frames[motion], 0) << motion << ": the knocks were never checked";
  }
  EXPECT_GT(first_frames, 0) << "no check's first frame was seen";
  EXPECT_GE(knocks_back, kMostKnocksBack) << "knocks repaired within 30 frames";
}

// Checks in the background (TrackerConfig::background_checks, handtrackd's latency setting): a frame
// that follows a tracked frame runs tracking's particles and, on the frame that takes a (re)start
// that won, one more fit of it: never a search, which is the search thread's. Knocked off as above
// (each frame waiting for the check under way: knock_off_and_track), the tracker is back within 30
// frames after most knocks: measured 7 of 9, all 7 within 3 frames. Not back: the knocks after frame
// 60 of flexex1 and fingercount, in their fists. In flexex1 the check's (re)start replaced the pose
// after 3 frames but held the fist 10-14 mm worse than the undisturbed tracker until frame 92; in
// fingercount the knocked-off pose had crept onto part of the fist when the (re)start came (118 mm
// off at confidence 0.58, more than the (re)start explained) and the next check came 30 frames
// later. Before the knuckles (2026-11-29) 8 of 9, random's knock after frame 140 not back. Over the
// 63 knocks of BackWithin30FramesAfterAGrossError with background checks all are back (3 not when
// last measured before the knuckles), with checks at once 62.
TEST(TrackingRecovery, ChecksInTheBackgroundKeepEveryFrameShortAndStillRepairAGrossError) {
  const PartForest& forest = testing::shipped_forest();
  TrackerConfig config = testing::paper_config(EnergyMode::kLateFusion);
  config.handedness = HandednessMode::kRight;
  config.background_checks = true;
  const int tracking_iterations = config.particles * config.optimizer.iterations;
  const int most_after_tracked = tracking_iterations + config.optimizer.iterations;
  constexpr int kMostKnocksBack = 7;  // of 3 motions x 3 knocks
  std::map<std::string_view, int> replaced;
  const int knocks_back = latency_knocks_back(config, forest, [&](auto motion, int i, const TrackerOutput& out,
                                                                  bool after_tracked, bool /*segmented_afresh*/) {
    if (!after_tracked) return;
    EXPECT_LE(out.iterations, most_after_tracked) << motion << " frame " << i << " ran a search";
    replaced[motion] += out.winning_particle < 0 ? 1 : 0;
  });
  for (const auto motion : kLatencyMotions) {
    std::printf("%-12s tracked poses replaced by a background check's (re)start: %d\n", std::string(motion).c_str(),
                replaced[motion]);
    EXPECT_GT(replaced[motion], 0) << motion << ": no background check replaced the knocked-off pose";
  }
  EXPECT_GE(knocks_back, kMostKnocksBack) << "knocks repaired within 30 frames";
}

// No hand: the state says so, and every number of the pose is zero (nothing invented).
void expect_no_hand(const TrackerOutput& out, const std::string& what) {
  EXPECT_EQ(out.state, TrackingState::kNoHand) << what;
  EXPECT_TRUE(out.params.isZero()) << what;
  for (const auto& tip : out.fingertips) EXPECT_TRUE(tip.isZero()) << what;
  for (const auto& joint : out.joints) EXPECT_TRUE(joint.isZero()) << what;
  EXPECT_EQ(out.confidence, 0.0) << what;
}

TEST(TrackingRecovery, EmptySceneIsNoHand) {
  Tracker tracker(testing::paper_config(EnergyMode::kDepthOnly));
  DepthImage empty = testing::motion_camera("pinch").render(0).depth;
  std::fill(empty.depth_mm.begin(), empty.depth_mm.end(), 0.0F);
  for (int i = 0; i < 3; ++i) expect_no_hand(tracker.track(empty), "empty frame " + std::to_string(i));
}

// The hand backs away beyond the working volume (far plane 600 mm, Sec. 4) and comes back.
TEST(TrackingRecovery, HandLeavingTheWorkingVolumeIsNoHandAndIsFoundAgain) {
  constexpr int kApproachFrames = 30;   // tracked in place first
  constexpr double kStepMm = 15.0;      // away per frame, then back
  constexpr int kAwayFrames = 40;       // 600 mm further: the whole hand (and forearm) beyond 600 mm
  constexpr int kTotalFrames = kApproachFrames + 2 * kAwayFrames + kRecoveryFrames;
  const PartForest& forest = testing::shipped_forest();
  Tracker tracker(testing::paper_config(EnergyMode::kLateFusion));
  auto camera = testing::motion_camera("fingerwave");
  const double far_mm = tracker.pose_tracker().config().input.far_mm;
  const double near_mm = tracker.pose_tracker().config().input.near_mm;
  synth::SynthFrame frame;
  int no_hand_frames = 0;
  int first_back_under_20mm = -1;
  for (int i = 0; i < kTotalFrames; ++i) {
    const int away = std::clamp(std::min(i - kApproachFrames, kApproachFrames + 2 * kAwayFrames - i), 0, kAwayFrames);
    auto pose = camera.pose(i);
    pose.translation_mm.z() += kStepMm * away;
    camera.render_pose(pose, i, frame);
    const auto out = tracker.track(frame.depth, &forest);
    const bool any_depth_in_volume = std::any_of(frame.depth.depth_mm.begin(), frame.depth.depth_mm.end(),
                                                 [&](float d) { return d >= near_mm && d <= far_mm; });
    if (!any_depth_in_volume) {
      expect_no_hand(out, "frame " + std::to_string(i) + ": nothing inside the working volume");
      ++no_hand_frames;
    }
    if (i >= kApproachFrames + 2 * kAwayFrames && first_back_under_20mm < 0 &&
        eval::fingertip_error_mm(out, frame.fingertips) < kRecoveredMm) {
      first_back_under_20mm = i;
    }
  }
  EXPECT_GT(no_hand_frames, 0) << "the hand never left the working volume: the test moves it too little";
  EXPECT_GE(first_back_under_20mm, 0) << "the hand is back in place but not tracked within 30 frames";
}

}  // namespace
}  // namespace handtrack
