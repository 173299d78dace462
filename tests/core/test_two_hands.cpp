// Two hands at once (issue 14): HandsTracker in the shipped configuration (late fusion with the
// shipped forest, handedness auto, 2 particles x 10 iterations per hand) on the two-hand scenes of
// handtrack-synth, and one hand with room for two.
//
// The bounds are what the tracker reaches now with some room (measured in docs/TRACKER.md, "Two
// hands"), so that a change that loses a hand, mixes up their sides or swaps their ids fails here.
#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/core/part_forest.hpp"
#include "handtrack/eval/scoring.hpp"
#include "handtrack/synth/synthetic_camera.hpp"
#include "handtrack/synth/two_hand_motions.hpp"
#include "synthetic_tracking.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <span>
#include <string>

namespace handtrack {
namespace {

constexpr uint64_t kSeed = 21;  // not used while tuning

TrackerConfig shipped_config(int max_hands) {
  TrackerConfig config;
  config.mode = EnergyMode::kLateFusion;
  config.max_hands = max_hands;
  return config;
}

using testing::shipped_forest;

// A two-hand scene's run, scored as handtrack-eval scores it (per ground-truth hand: matched by
// position, its error, side and identity swaps; phantom hands), and every hand id seen.
struct SceneRun {
  eval::SequenceScore score;
  std::vector<uint32_t> ids_seen;
  uint32_t last_id_of_hand_1 = 0;
  [[nodiscard]] const eval::SequenceScore& hand(int k) const { return score.hands.at(static_cast<size_t>(k)); }
};

// Tracks `frames` of a two-hand scene of subject `seed`; hand 1 is out of view (no depth at its
// pixels, forearm too) in frames [hidden_from, hidden_to).
// The camera's arrangement (TrackerConfig::arrangement) is the scene's; a head-mounted scene is
// rendered over its table, as handtrack-synth renders it.
SceneRun track_scene(const std::string& motion, int frames, int hidden_from = -1, int hidden_to = -1,
                     uint64_t seed = kSeed) {
  synth::SynthOptions options;
  options.motion = motion;
  options.frames = frames;
  options.seed = seed;
  const bool head_mounted = synth::two_hand_view(motion) == synth::View::kHeadMounted;
  if (head_mounted) options.background = synth::Background::kTable;
  synth::SyntheticCamera camera(options);
  TrackerConfig config = shipped_config(2);
  if (head_mounted) config.arrangement = CameraArrangement::kHeadMounted;
  HandsTracker tracker(config);
  eval::HandsScorer scorer(motion, {Handedness::kRight, Handedness::kLeft});
  SceneRun run;
  synth::SynthFrame frame;
  for (int i = 0; i < frames; ++i) {
    camera.render(i, frame);
    const bool hidden = i >= hidden_from && i < hidden_to;
    std::array<Fingertips, 2> truth{frame.hands[0].fingertips, frame.hands[1].fingertips};
    EXPECT_EQ(frame.hands[1].hand, synth::Handedness::kLeft);
    if (hidden) {
      for (size_t p = 0; p < frame.depth.depth_mm.size(); ++p) {
        if (frame.hand_index.pixels[p] == 2) frame.depth.depth_mm[p] = 0.0F;
      }
      truth[1] = Fingertips{};  // not in view: not scored
    }
    const HandsOutput out = tracker.track(frame.depth, &shipped_forest());
    const std::span<const TrackerOutput> tracked(out.hands.data(), static_cast<size_t>(out.count));
    const eval::HandMatch match = scorer.add(tracked, truth);
    for (const TrackerOutput& o : tracked) {
      if (std::find(run.ids_seen.begin(), run.ids_seen.end(), o.hand_id) == run.ids_seen.end()) {
        run.ids_seen.push_back(o.hand_id);
      }
    }
    if (match.tracked_of_truth[1] >= 0) {
      run.last_id_of_hand_1 = tracked[static_cast<size_t>(match.tracked_of_truth[1])].hand_id;
    }
  }
  run.score = scorer.finish(0.0);
  for (int k = 0; k < 2; ++k) {
    const eval::SequenceScore& h = run.hand(k);
    std::printf("%s hand %d: %d of %d frames posed, %.1f mm, side right %d, id swaps %d; phantom frames %d\n",
                motion.c_str(), k, h.posed_frames, h.frames, h.mean_error_mm, h.hand_correct, h.identity_swaps,
                run.score.phantom_frames);
  }
  return run;
}

// Each hand of `run` posed in at least `min_posed` frames, on its own side in at least `min_pct` %
// of them, and never given the other hand's id.
void expect_sides_held(const SceneRun& run, int min_posed, int min_pct) {
  for (int k = 0; k < 2; ++k) {
    const eval::SequenceScore& h = run.hand(k);
    EXPECT_GE(h.posed_frames, min_posed) << "hand " << k;
    EXPECT_GE(h.hand_correct, h.posed_frames * min_pct / 100) << "hand " << k << ": fitted as the other side too often";
    EXPECT_EQ(h.identity_swaps, 0) << "hand " << k;
  }
}

TEST(TwoHands, BothHandsTrackedApartEachWithItsSide) {
  const SceneRun run = track_scene("two_apart", 120);
  for (int k = 0; k < 2; ++k) {
    const eval::SequenceScore& h = run.hand(k);
    EXPECT_GE(h.posed_frames, 115);
    EXPECT_LE(h.mean_error_mm, 15.0);
    EXPECT_GE(h.hand_correct, h.posed_frames * 95 / 100);
    EXPECT_EQ(h.identity_swaps, 0);
  }
  EXPECT_EQ(run.score.phantom_frames, 0);
}

TEST(TwoHands, IdsFollowTheHandsWhenTheyCross) {
  // The right hand passes in front of the left, and back: each keeps its id throughout.
  const SceneRun run = track_scene("two_cross", 240);
  for (int k = 0; k < 2; ++k) {
    EXPECT_GE(run.hand(k).posed_frames, 200);
    EXPECT_EQ(run.hand(k).identity_swaps, 0);
  }
}

TEST(TwoHands, AHandKeepsItsSideWhereTheOtherHandsSideIsTheClearerChoice) {
  // two_cross of subject 6 (a sequence of the benchmark, scripts/eval-two-hands): the crossing
  // right hand's own evidence stays short of the margin while the left hand's is clearer. When
  // its evidence merely left the tie it took the left hand's side, in 23 of 300 frames (92.3 %
  // right); now the clearer hand decides the pair (Tracker::weigh): 100 %.
  expect_sides_held(track_scene("two_cross", 300, -1, -1, 6), 290, 97);
}

TEST(TwoHands, ClappingHandsNotYetToldApartTakeTheSidesTheirPlacesSay) {
  // two_clap of subject 4 (a sequence of the benchmark): flat hands, palms facing, side-on to the
  // camera, whose evidence never leaves the tie. Each hand followed the other's side, and the pair
  // went to the side whichever strayed first: both wrong in 32 % of the frames. Now, until either
  // side has been told, the hand on the image's left is expected to be the right hand
  // (HandsTracker::face_other_hands).
  expect_sides_held(track_scene("two_clap", 300, -1, -1, 4), 290, 98);
}

TEST(TwoHands, AHeadMountedPairNotYetToldApartTakesTheSidesAHeadsetSees) {
  // two_reach of subject 4 (a sequence of the benchmark): both hands reaching forward under a
  // head-mounted camera, their backs toward it, the right hand on the image's right. Expected the
  // way a camera facing the user sees a pair, both were the other side in 21 % of the frames;
  // told the camera is head-mounted (TrackerConfig::arrangement), the left hand is right in all of
  // them and the right hand in 89 % (HandsTracker::face_other_hands).
  expect_sides_held(track_scene("two_reach", 300, -1, -1, 4), 290, 85);
}

TEST(TwoHands, AHandThatLeavesComesBackWithAFreshId) {
  // Hand 1 leaves the view for frames 40-79 (longer than TrackerConfig::hidden_hand_frames): while
  // it is away one hand is reported, and when it returns it gets an id never given before (3:
  // hands 1 and 2 were the first two).
  const SceneRun run = track_scene("two_apart", 120, 40, 80);
  EXPECT_EQ(run.score.phantom_frames, 0);
  EXPECT_EQ(run.ids_seen.size(), 3U);
  EXPECT_EQ(run.last_id_of_hand_1, 3U);
  EXPECT_EQ(run.hand(0).identity_swaps, 0);
}

// The same one-hand frames with max_hands 1 and 2 give the same poses, and no second hand; frames
// [away_from, away_to) have no depth (the hand has left the view).
void expect_as_with_room_for_one(const synth::SynthOptions& options, int away_from, int away_to) {
  synth::SyntheticCamera camera(options);
  Tracker one(shipped_config(1));  // one hand, as before HandsTracker
  HandsTracker two(shipped_config(2));
  synth::SynthFrame frame;
  int phantoms = 0;
  for (int i = 0; i < options.frames; ++i) {
    camera.render(i, frame);
    const bool away = i >= away_from && i < away_to;
    if (away) std::fill(frame.depth.depth_mm.begin(), frame.depth.depth_mm.end(), 0.0F);
    const TrackerOutput a = one.track(frame.depth, &shipped_forest());
    const HandsOutput b = two.track(frame.depth, &shipped_forest());
    phantoms += b.count > 1 ? 1 : 0;
    if (away) {
      EXPECT_EQ(b.count, 0) << "frame " << i;
      continue;
    }
    ASSERT_NE(a.state, TrackingState::kNoHand) << "frame " << i;
    ASSERT_GE(b.count, 1) << "frame " << i;
    EXPECT_EQ(a.params, b.hands[0].params) << "frame " << i;
  }
  EXPECT_EQ(phantoms, 0);
}

TEST(TwoHands, OneHandWithRoomForTwoIsTrackedAsWithRoomForOne) {
  // Also when the hand leaves the view (frames 40-44 without depth) and returns: alone, it has
  // left, and it is found again at once (not held back as a hand hidden behind another).
  synth::SynthOptions options;
  options.motion = "fingercount";
  options.frames = 120;
  options.seed = kSeed;
  expect_as_with_room_for_one(options, 40, 45);
}

TEST(TwoHands, AForearmReachingBackThroughTheFarPlaneIsNoSecondHand) {
  // random, subject 1: from frame 60 on the forearm, cut off from the tracked hand by the depth
  // step at the wrist, goes back through the far plane and comes as near as the hand. Taken for a
  // hand held far (its reach beyond 100 mm in front of the far plane), it was a phantom second
  // hand in 240 of 300 frames.
  // The frame is then shared out between the hand and that surface, which moves the hand's pose
  // by fractions of a mm from max_hands 1's: one hand and no other is asserted, not the same pose.
  synth::SynthOptions options;
  options.motion = "random";
  options.frames = 300;
  options.seed = 1;
  synth::SyntheticCamera camera(options);
  HandsTracker tracker(shipped_config(2));
  synth::SynthFrame frame;
  int phantoms = 0;
  for (int i = 0; i < 90; ++i) {
    camera.render(i, frame);
    const HandsOutput out = tracker.track(frame.depth, &shipped_forest());
    ASSERT_GE(out.count, 1) << "frame " << i;
    phantoms += out.count > 1 ? 1 : 0;
  }
  EXPECT_EQ(phantoms, 0);
}

TEST(TwoHands, OneHandOnADeskWithRoomForTwoIsTrackedAsWithRoomForOne) {
  // Hand and desk are one surface until the desk's plane is taken out (support_plane.hpp), in the
  // hands' split as in each hand's segmentation: without it in the split, 129 of 150 frames of
  // this pinch had no hand with max_hands 2.
  synth::SynthOptions options;
  options.motion = "pinch";
  options.frames = 60;
  options.seed = kSeed;
  options.background = synth::Background::kDesk;
  expect_as_with_room_for_one(options, -1, -1);
}

}  // namespace
}  // namespace handtrack
