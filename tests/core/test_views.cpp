// Every view (issue "Every hand, every view"): the shipped configuration (late fusion with the
// shipped forest, handedness auto, 2 particles x 10 iterations) on one motion in each camera
// arrangement of handtrack-synth, 120 frames, three subjects not used while tuning (seeds 21-23),
// noise on. A bound holds for the three pooled: one subject decides nothing (a change to the
// quadtree moved fingers-away left of seed 21 from 11.2 to 25.2 mm while the broadened benchmark
// gained 0.5 mm over nine subjects; docs/TRACKER.md, "Tests over three subjects").
//
// The bounds are what the tracker reaches now with some room, so that a change that loses a view
// fails here; they are not the goal (every view <= 20 mm, handedness >= 98 %), which the
// back, side, fingers-away and head-mounted views still miss (docs/TRACKER.md, "Every view").
#include "handtrack/core/energy.hpp"
#include "handtrack/core/kinematics.hpp"
#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/tracker.hpp"
#include "handtrack/core/unseen_fingers.hpp"
#include "handtrack/synth/synthetic_camera.hpp"
#include "handtrack/synth/views.hpp"
#include "synthetic_tracking.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <string>

namespace handtrack {
namespace {

constexpr int kFrames = 120;
constexpr std::array<uint64_t, 3> kSeeds = {21, 22, 23};

struct ViewCase {
  synth::View view;
  synth::Handedness hand;
  double max_mean_mm;           // mean fingertip error over the frames with a pose
  double min_handedness_share;  // of the frames with a pose, reported as the hand shown
  synth::Background background = synth::Background::kBody;
  double ball_radius_mm = 0.0;  // a ball held against the palm (synth --ball)
  const char* motion = "pinch";
  synth::Proportions proportions = synth::Proportions::kMean;
};

// The shipped configuration: late fusion with the shipped forest.
TrackerConfig shipped_config() {
  TrackerConfig config;
  config.mode = EnergyMode::kLateFusion;
  return config;
}

// The same without E_unseen (w_u = 0).
TrackerConfig without_unseen_fingers() {
  TrackerConfig config = shipped_config();
  config.weights.unseen_fingers = 0.0;
  return config;
}

testing::OneHandRun track_view(const ViewCase& c, const PartForest& forest, uint64_t seed,
                               const TrackerConfig& config = shipped_config()) {
  synth::SynthOptions options;
  options.motion = c.motion;
  options.frames = kFrames;
  options.seed = seed;
  options.hand = c.hand;
  options.view = c.view;
  options.background = c.background;
  options.ball_radius_mm = c.ball_radius_mm;
  options.proportions = c.proportions;
  return testing::track_one_hand(options, config, &forest);
}

// `c` tracked for each of `seeds`, pooled (the mean over every posed frame), each printed.
template <typename Seeds>
testing::OneHandRun track_subjects(const ViewCase& c, const PartForest& forest, const Seeds& seeds,
                                   const TrackerConfig& config = shipped_config()) {
  testing::OneHandRun pooled;
  for (const uint64_t seed : seeds) {
    const testing::OneHandRun run = track_view(c, forest, seed, config);
    std::printf("%s %s %s seed %llu: %.1f mm, %d of %d frames posed, %d as the hand shown\n", c.motion,
                std::string(synth::view_name(c.view)).c_str(), std::string(synth::handedness_name(c.hand)).c_str(),
                static_cast<unsigned long long>(seed), run.mean_error_mm(), run.posed, kFrames, run.reported_as_shown);
    pooled.add(run);
  }
  return pooled;
}

class EveryView : public ::testing::TestWithParam<ViewCase> {};

TEST_P(EveryView, TrackedAsTheHandItIs) {
  const ViewCase& c = GetParam();
  const PartForest& forest = testing::shipped_forest();
  const testing::OneHandRun run = track_subjects(c, forest, kSeeds);
  const std::string name = std::string(c.motion) + " " + std::string(synth::view_name(c.view)) + " " +
                           std::string(synth::handedness_name(c.hand)) +
                           " on " + std::string(synth::background_name(c.background)) +
                           (c.ball_radius_mm > 0.0 ? " holding a ball" : "") +
                           (c.proportions == synth::Proportions::kVaried ? " of varied proportions" : "");
  const int frames = kFrames * static_cast<int>(kSeeds.size());
  std::printf("%s: %.1f mm, %d of %d frames posed, %d as the hand shown\n", name.c_str(), run.mean_error_mm(), run.posed,
              frames, run.reported_as_shown);
  EXPECT_GE(run.posed, frames * 95 / 100) << name << ": a pose in at least 95 % of the frames";
  EXPECT_LE(run.mean_error_mm(), c.max_mean_mm) << name;
  EXPECT_GE(run.reported_as_shown, c.min_handedness_share * run.posed) << name << ": handedness";
}

std::string case_name(const ::testing::TestParamInfo<ViewCase>& info) {
  std::string name = std::string(info.param.motion) + "_" + std::string(synth::view_name(info.param.view)) + "_" +
                     std::string(synth::handedness_name(info.param.hand));
  if (info.param.background != synth::Background::kBody) {
    name += '_';
    name += synth::background_name(info.param.background);
  }
  if (info.param.ball_radius_mm > 0.0) name += "_ball";
  if (info.param.proportions == synth::Proportions::kVaried) name += "_varied";
  for (char& ch : name) {
    if (ch == '-') ch = '_';
  }
  return name;
}

// Measured at seed 21 when this test was written: palm 5.6 (right) and 4.2 mm (left), back 19.0 mm
// with 74 % of the frames reported as the right hand, side 4.6, fingers-toward 9.0, fingers-away
// 15.6 (left), head-mounted 39.6 mm; every other view 100 % the hand shown. With the free-space
// term E_free: palm 5.5 / 4.8, back 16.1 (74 %), side 6.9, fingers-toward 8.5, fingers-away 14.2,
// head-mounted 28.2 mm (its bound lowered from 55 to 40 mm). With the hand chosen by evidence over
// frames (Tracker::weigh): back 12.9 mm with 85 % of the frames the right hand (its bounds lowered
// from 30 to 20 mm and raised from 60 to 80 %), the other views unchanged. With the forest
// retrained with held balls and the regions it calls background dropped: palm 4.2 / 4.7, back 10.9
// (100 %), side 7.1, fingers-toward 8.3, fingers-away 11.2, head-mounted 28.5 mm; on a desk 5.8,
// 7.2, 11.6 mm. Over seeds 21-23 pooled (2026-11-26): palm 5.2 / 4.8, back 15.6 mm (91 % the
// right hand), side 7.0, fingers-toward 6.9, fingers-away 13.3, head-mounted 29.5 mm; on a desk
// 5.5, 6.7, 13.2 mm (the back 96 % the right hand); holding a ball 13.0 mm. With E_sim's coverage
// cap while tracking (2026-11-27): the back 12.9 mm but 71 % the right hand (its bound lowered from
// 80 to 65 %), on a desk 14.3 mm, 87 % (90 -> 80 %). On these subjects the pinch seen from the back
// starts as a tie that the palm-toward rule gives to the left hand, and the evidence takes longer
// to leave it (seed 23: frame 19 -> 65). Over every motion of the broadened benchmark the back
// view's handedness gained on three of four sets of subjects and lost on these (right hands 92.9
// -> 89.3 %; docs/TRACKER.md, "E_sim's coverage cap"). With the surface fronts (2026-11-29):
// head-mounted 15.9 mm (its bound lowered from 40 to 25 mm).
INSTANTIATE_TEST_SUITE_P(
    ShippedConfiguration, EveryView,
    ::testing::Values(ViewCase{synth::View::kPalm, synth::Handedness::kRight, 12.0, 0.98},
                      ViewCase{synth::View::kPalm, synth::Handedness::kLeft, 12.0, 0.98},
                      ViewCase{synth::View::kBack, synth::Handedness::kRight, 20.0, 0.65},
                      ViewCase{synth::View::kSide, synth::Handedness::kRight, 15.0, 0.98},
                      ViewCase{synth::View::kFingersToward, synth::Handedness::kRight, 20.0, 0.98},
                      ViewCase{synth::View::kFingersAway, synth::Handedness::kLeft, 25.0, 0.98},
                      ViewCase{synth::View::kHeadMounted, synth::Handedness::kRight, 25.0, 0.98}),
    case_name);

// A hand resting on a desk (synth::Background::kDesk): hand and desk are one connected surface,
// which segmentation takes apart by the desk's plane (support_plane.hpp). Without that, no frame
// had a hand or the hand took in the desk around it (docs/TRACKER.md, "Segmentation"). Measured at
// seed 21: palm right 7.0, side left 6.5, back right 12.6 mm, every frame the hand shown.
INSTANTIATE_TEST_SUITE_P(
    OnADesk, EveryView,
    ::testing::Values(ViewCase{synth::View::kPalm, synth::Handedness::kRight, 12.0, 0.98, synth::Background::kDesk},
                      ViewCase{synth::View::kSide, synth::Handedness::kLeft, 15.0, 0.98, synth::Background::kDesk},
                      ViewCase{synth::View::kBack, synth::Handedness::kRight, 25.0, 0.8, synth::Background::kDesk}),
    case_name);

// A ball (35 mm radius) held against the palm: segmentation keeps it with the hand (it touches the
// palm), and the regions the forest labels background leave the hand (DepthInputConfig::
// drop_background; the shipped forest learnt held balls as background, data/part_forest.md).
// Measured at seed 21: 13.7 mm; 92.7 mm before (the forest of all views, nothing dropped), 25.1
// dropping with that forest, 30.8 with the shipped forest and nothing dropped.
INSTANTIATE_TEST_SUITE_P(HoldingABall, EveryView,
                         ::testing::Values(ViewCase{synth::View::kPalm, synth::Handedness::kRight, 20.0, 0.98,
                                                    synth::Background::kBody, 35.0}),
                         case_name);

// Hands of other proportions than the model's (synth::Proportions::kVaried: every finger's length
// +-6 %, the fingers' girth and the palm's thickness +-15 %, beside the size): the tracker's model
// scales by length, width and sigma only, and is held to the bounds of the mean adult's
// proportions above. Measured when written (seeds 21-23 pooled): palm 4.6 mm, side 4.8, back 13.0
// with 74 % of the frames the right hand (the same subjects' mean proportions: back 10.2 mm, 90 %;
// docs/TRACKER.md, "Hands of other proportions").
INSTANTIATE_TEST_SUITE_P(
    OtherProportions, EveryView,
    ::testing::Values(ViewCase{synth::View::kPalm, synth::Handedness::kRight, 12.0, 0.98, synth::Background::kBody, 0.0,
                               "pinch", synth::Proportions::kVaried},
                      ViewCase{synth::View::kSide, synth::Handedness::kLeft, 15.0, 0.98, synth::Background::kBody, 0.0,
                               "pinch", synth::Proportions::kVaried},
                      ViewCase{synth::View::kBack, synth::Handedness::kRight, 20.0, 0.65, synth::Background::kBody,
                               0.0, "pinch", synth::Proportions::kVaried}),
    case_name);

// Fists seen from behind: flexex1 under a head-mounted camera closes into a fist within these 120
// frames. Its fingers go toward the fist where the hand reaches no farther than the knuckles
// (unseen_fingers.hpp). Measured when written: 31.8 mm (29.3 / 32.9 / 33.3 on seeds 21-23); with
// every finger held at the half curl, as before, 34.4 mm (31.9 / 34.0 / 37.2), which the bound fails.
INSTANTIATE_TEST_SUITE_P(FistsFromBehind, EveryView,
                         ::testing::Values(ViewCase{synth::View::kHeadMounted, synth::Handedness::kRight, 33.0, 0.98,
                                                    synth::Background::kBody, 0.0, "flexex1"}),
                         case_name);

// A flat hand seen from the back (adbadd: the fingers spread and close, never curl) is the mirror
// image of the other hand's palm through the hand's plane. The part labels favour the palm-toward
// fit, the depth the true one, by a few hundredths of the fit score a frame, so single sequences
// still go either way: the share over both hands and four subjects (docs/TRACKER.md, "Mirror images
// through the hand's plane"). Measured: 810 of 960 frames (84 %), 14.7 mm; before that rule 433
// of 960 (45 %), 19.3 mm.
TEST(FlatHandFromTheBack, MostFramesAreTheHandItIs) {
  const PartForest& forest = testing::shipped_forest();
  constexpr std::array<uint64_t, 4> kFlatSeeds = {21, 22, 23, 24};
  testing::OneHandRun both;
  for (const synth::Handedness hand : {synth::Handedness::kRight, synth::Handedness::kLeft}) {
    const ViewCase flat{synth::View::kBack, hand, 0.0, 0.0, synth::Background::kBody, 0.0, "adbadd"};
    both.add(track_subjects(flat, forest, kFlatSeeds));
  }
  EXPECT_GE(both.reported_as_shown, 0.7 * both.posed)
      << both.reported_as_shown << " of " << both.posed << " frames reported as the hand shown";
  EXPECT_LE(both.mean_error_mm(), 17.0);
}

// Fists seen from the back: the fingers curl behind the hand, where neither the depth nor the part
// labels see them, and were fitted stretched out behind it. E_unseen curls the fingers the labels
// do not see on a hand facing the camera (unseen_fingers.hpp); on the two motions that make fists,
// on three subjects w_u was not measured on (docs/TRACKER.md, "Unseen fingers curl"). Measured:
// 26.4 mm with it, 30.2 mm without (better on five of the six sequences).
TEST(FistsFromTheBack, FingersTheCameraCannotSeeCurl) {
  const PartForest& forest = testing::shipped_forest();
  const TrackerConfig without = without_unseen_fingers();
  testing::OneHandRun with_prior;
  testing::OneHandRun without_prior;
  for (const char* motion : {"flexex1", "fingercount"}) {
    const ViewCase fists{synth::View::kBack, synth::Handedness::kRight, 0.0, 0.0, synth::Background::kBody, 0.0, motion};
    with_prior.add(track_subjects(fists, forest, kSeeds));
    without_prior.add(track_subjects(fists, forest, kSeeds, without));
  }
  std::printf("fists from the back: %.1f mm with E_unseen, %.1f mm without\n", with_prior.mean_error_mm(),
              without_prior.mean_error_mm());
  EXPECT_LT(with_prior.mean_error_mm(), without_prior.mean_error_mm() - 2.5);
}

// Seen from behind, the fingers of a fist go toward the relaxed fist and those of an open hand stay
// at the half curl (unseen_fingers.hpp): a head-mounted flexex1's fist (frame 65, the middle finger
// curled about 140 deg from the back of the hand) and its open hand (frame 140, about 10 deg), each
// built as the tracker builds a frame (segmented with its own pose's hint, the rendered part
// labels) and weighed from its own pose. Rendered without noise: a flying pixel between the hand
// and the table 140 mm behind it counts as reach (with noise, this fist's index, ring and little
// finger read 87-131 mm at their true pose). Measured when written (subject 21): k_f = 1 for each
// of the fist's fingers, 0 for each of the open hand's.
TEST(FistsFromBehind, TheHandBeyondTheKnucklesTellsAFistFromAnOpenHand) {
  synth::SynthOptions options;
  options.motion = "flexex1";
  options.view = synth::View::kHeadMounted;
  options.seed = kSeeds[0];
  options.noise = false;
  synth::SyntheticCamera camera(options);
  const HandModel model = HandModel::default_adult();
  DepthInputBuilder builder(input_config(shipped_config()));
  const auto weigh = [&](int frame) {
    const synth::SynthFrame rendered = camera.render(frame);
    const PoseParams pose = rendered.pose.to_params();
    PoseTracker posed{shipped_config()};
    posed.override_pose(pose);
    const FixedLabels labels(&rendered.labels.pixels);
    const DepthInput& input = builder.build(rendered.depth, posed.hint(), &labels);
    return unseen_fingers(input, PosedHand(model, pose));
  };
  // k_f, each finger's share of h_f that goes to the fist (h_f = held + that share).
  const auto to_fist = [](const UnseenFingers& u, int f) {
    const auto i = static_cast<size_t>(f);
    return 1.0 - u.held[i] / (u.held[i] + u.weight[i]);
  };
  const UnseenFingers open = weigh(140);
  const UnseenFingers fist = weigh(65);
  double open_mean = 0.0;
  double fist_mean = 0.0;
  for (const int f : {kIndex, kMiddle, kRing, kLittle}) {
    EXPECT_GT(open.held[static_cast<size_t>(f)], 0.2) << "finger " << f << ": seen from behind, held";
    // u_f's own part (labels on a hand facing the camera) is small in this view.
    EXPECT_LT(to_fist(open, f), 0.15) << "finger " << f << ": an open hand is not pulled to a fist";
    open_mean += to_fist(open, f) / 4.0;
    fist_mean += to_fist(fist, f) / 4.0;
  }
  std::printf("k_f, index..little: fist %.2f %.2f %.2f %.2f, open hand %.2f %.2f %.2f %.2f\n", to_fist(fist, kIndex),
              to_fist(fist, kMiddle), to_fist(fist, kRing), to_fist(fist, kLittle), to_fist(open, kIndex),
              to_fist(open, kMiddle), to_fist(open, kRing), to_fist(open, kLittle));
  EXPECT_GT(fist_mean, 0.8) << "a fist's fingers go to the fist";
  EXPECT_GT(fist_mean, open_mean + 0.6);
  EXPECT_EQ(fist.weight[kThumb], 0.0);
  EXPECT_EQ(fist.held[kThumb], 0.0);
}

// Beside another hand E_unseen is off: that hand can hide an outstretched finger as well
// (PoseTracker::optimise; docs/TRACKER.md, "Unseen fingers curl": two_cross's left hand behind the
// right, 9.9 -> 21.6 mm with it). A hand far out of reach (E_hand is 0 there) given as the other
// hand: the fists from the back are then tracked exactly as with w_u = 0, while alone the same
// frames are tracked otherwise (so the prior acts on them and the first comparison can fail).
TEST(FistsFromTheBack, NoCurlBesideAnotherHand) {
  const PartForest& forest = testing::shipped_forest();
  synth::SynthOptions options;
  options.motion = "flexex1";
  options.view = synth::View::kBack;
  options.frames = 60;
  options.seed = kSeeds[0];
  const TrackerConfig without = without_unseen_fingers();
  Tracker beside_hand(shipped_config());
  Tracker alone(shipped_config());
  Tracker no_prior(without);
  PoseParams far_away = PoseParams::Zero();
  far_away.segment<3>(kTranslationParam) = Eigen::Vector3d(3000.0, 0.0, 400.0);
  const PosedHand far_hand(beside_hand.model(), far_away);
  HandObstacle as_right;
  HandObstacle as_left;
  as_right.assign(beside_hand.model(), far_hand, false);
  as_left.assign(beside_hand.model(), far_hand, true);
  beside_hand.set_other_hand(&as_right, &as_left);
  synth::SyntheticCamera camera(options);
  synth::SynthFrame frame;
  int frames_differing_alone = 0;
  for (int i = 0; i < options.frames; ++i) {
    camera.render(i, frame);
    const TrackerOutput a = beside_hand.track(frame.depth, &forest);
    const TrackerOutput b = no_prior.track(frame.depth, &forest);
    const TrackerOutput c = alone.track(frame.depth, &forest);
    ASSERT_EQ(a.state, b.state) << "frame " << i;
    for (size_t t = 0; t < a.fingertips.size(); ++t) {
      ASSERT_EQ(a.fingertips[t], b.fingertips[t]) << "frame " << i << ", fingertip " << t;
    }
    frames_differing_alone += a.fingertips != c.fingertips ? 1 : 0;
  }
  EXPECT_GT(frames_differing_alone, 10) << "E_unseen no longer acts on these frames: the test shows nothing";
}

// A fist seen along its fingers: fingercount's first 30 frames (the hand a fist, then its index
// rising) with the fingers pointing away from and toward the camera (docs/TRACKER.md, "A fist at
// a (re)start").
constexpr int kFistFrames = 30;

struct FistRun {
  double mean_mm = 0.0;  // mean fingertip error over the frames
  int right = 0;         // frames reported as the right hand (the hand shown)
};

// The first kFistFrames frames, tracked from the true pose on frame 0 (`given_its_pose`) or
// started by the (re)start search as shipped.
FistRun fist_tracked(synth::View view, uint64_t seed, bool given_its_pose) {
  synth::SynthOptions options;
  options.motion = "fingercount";
  options.seed = seed;
  options.view = view;
  options.background = synth::default_background(options.motion, view);
  synth::SyntheticCamera camera(options);
  synth::SynthFrame frame;
  Tracker tracker(shipped_config());
  FistRun run;
  for (int i = 0; i < kFistFrames; ++i) {
    camera.render(i, frame);
    if (i == 0 && given_its_pose) {
      TrackerOutput start;
      start.params = frame.pose.to_params();
      start.handedness = Handedness::kRight;
      start.state = TrackingState::kTracking;
      tracker.resume(start);
    }
    const TrackerOutput out = tracker.track(frame.depth, &testing::shipped_forest());
    EXPECT_NE(out.state, TrackingState::kNoHand) << "frame " << i;
    run.mean_mm += testing::fingertip_error_mm(out, frame) / kFistFrames;
    run.right += out.handedness == Handedness::kRight ? 1 : 0;
  }
  return run;
}

// fist_tracked on each of the suite's subjects (printed): the mean of their mean errors, and
// the frames reported right over all of them.
FistRun fist_tracked_on_each_subject(synth::View view, bool given_its_pose) {
  FistRun all;
  for (const uint64_t seed : kSeeds) {
    const FistRun run = fist_tracked(view, seed, given_its_pose);
    std::printf("fingercount %s seed %llu, frames 0-%d%s: %.1f mm, %d reported right\n",
                std::string(synth::view_name(view)).c_str(), static_cast<unsigned long long>(seed), kFistFrames - 1,
                given_its_pose ? " from the true pose" : "", run.mean_mm, run.right);
    all.mean_mm += run.mean_mm / static_cast<double>(kSeeds.size());
    all.right += run.right;
  }
  return all;
}

struct FistBound {
  synth::View view;
  double max_mean_mm;  // of fist_tracked_on_each_subject
};
constexpr int kFistFramesOnEachSubject = static_cast<int>(kSeeds.size()) * kFistFrames;

// Tracking holds the fist once given its pose. Measured on seeds 21-23 when written: fingers away
// 15.3 / 19.0 / 20.0 mm, toward 13.8 / 14.2 / 14.0; with the paper's w_c while tracking 25.4 /
// 23.5 / 34.6 and 16.2-16.4 mm.
TEST(FistSeenAlongItsFingers, IsHeldOnceTrackingIsGivenItsPose) {
  for (const FistBound& c :
       {FistBound{synth::View::kFingersAway, 24.0}, FistBound{synth::View::kFingersToward, 18.0}}) {
    const FistRun run = fist_tracked_on_each_subject(c.view, true);
    EXPECT_LT(run.mean_mm, c.max_mean_mm) << synth::view_name(c.view);
    EXPECT_EQ(run.right, kFistFramesOnEachSubject) << synth::view_name(c.view);
  }
}

// Pointing toward or away from the camera, the fist is found by the (re)start search itself: a
// segmented hand no longer than a fist, whose axis lies in the image plane, is also started as a
// fist tipped toward and away from the camera (StartSearch::place). Measured on seeds 21-23 when
// written: toward 17.7 / 14.3 / 15.0 mm, away 26.4 / 24.2 / 27.2 mm, every frame reported right;
// without the tipped fists toward 67.7 / 63.5 / 63.5 mm, away 82.7 / 65.4 / 46.7 mm.
TEST(FistSeenAlongItsFingers, IsStartedRight) {
  for (const FistBound& c :
       {FistBound{synth::View::kFingersToward, 25.0}, FistBound{synth::View::kFingersAway, 35.0}}) {
    const FistRun run = fist_tracked_on_each_subject(c.view, false);
    EXPECT_LT(run.mean_mm, c.max_mean_mm) << synth::view_name(c.view);
    EXPECT_GE(run.right, kFistFramesOnEachSubject * 9 / 10) << synth::view_name(c.view);
  }
}

// Seen from behind along fingers that point away from the camera (a head-mounted camera), the
// back of the hand and the fingers are surfaces at a slant, which lie further in front of the
// model's Gaussians than one sigma_h (surface_fronts.hpp). With eq. 7's fronts the fits tip the
// hand toward the camera and slide it nearer. Measured on seeds 21-23 when written: pinch 15.7 /
// 15.0 / 17.0 mm with the surface fronts (15.9 pooled), 16.6 / 18.3 / 20.9 mm with eq. 7's
// (EnergyWeights::slant_front = 1; 18.6 pooled).
TEST(HeadMountedPinch, IsHeldWhereTheCameraSeesTheBackOfTheHand) {
  const PartForest& forest = testing::shipped_forest();
  const ViewCase c{synth::View::kHeadMounted, synth::Handedness::kRight, 0.0, 0.0};
  TrackerConfig papers_fronts = shipped_config();
  papers_fronts.weights.slant_front = 1.0;
  const double shipped = track_subjects(c, forest, kSeeds).mean_error_mm();
  const double papers = track_subjects(c, forest, kSeeds, papers_fronts).mean_error_mm();
  std::printf("head-mounted pinch: %.1f mm with the surface fronts, %.1f mm with eq. 7's\n", shipped, papers);
  EXPECT_LT(shipped, papers - 1.5);
}

// A hand held 80 mm farther than the motion holds it (handtrack-synth --depth-offset 80), its
// forearm reaching back through the far plane (600 mm): the far plane cuts as large a share of the
// small outline as of a shoulder reaching into the working volume (docs/TRACKER.md, "Hands nearer and farther").
// Before the rule asked how far the surface reaches in (kMinHandReachMm), 193 of 25,200 such
// frames of the benchmark's scenes had no hand, many of them fists, the smallest outlines.
// Measured on seeds 21-23 when written: a pose in 900 of 900 frames, 7.7 mm; before, in 881.
TEST(HandHeldFar, IsFoundThoughItsForearmReachesBackThroughTheFarPlane) {
  testing::OneHandRun run;
  int frames = 0;
  for (const uint64_t seed : kSeeds) {
    synth::SynthOptions options;
    options.motion = "flexex1";
    options.seed = seed;
    options.depth_offset_mm = 80.0;
    run.add(testing::track_one_hand(options, shipped_config(), &testing::shipped_forest()));
    frames += options.frames;
  }
  std::printf("flexex1 80 mm farther: a pose in %d of %d frames, %.1f mm\n", run.posed, frames, run.mean_error_mm());
  EXPECT_GE(run.posed, frames * 99 / 100);
  EXPECT_LT(run.mean_error_mm(), 15.0);
}

// A hand without its arm (handtrack-synth --arm none: a renderer's hand model cut at the wrist):
// neither end of the segmented hand leaves the image, so the end nearer the camera was taken for
// the hand's, and with the fingers pointing away (a desk camera's pointing hand, a head-mounted
// camera's view) that is the wrist: the fit lay end to end reversed, the mirror image. Now a
// surface no longer than a hand has its fingers at the end farther from its widest part.
// Measured on seeds 21-23 when written: pinch fingers-away 6.4 mm, every frame right (before: 115.6
// mm, 25 %); head-mounted 22.6 mm, every frame right (94.6 mm, 16 %).
TEST(HandWithoutItsArm, IsStartedWithItsFingersAtTheEndFarFromThePalm) {
  struct Bound {
    synth::View view;
    double max_mean_mm;
  };
  for (const Bound& b : {Bound{synth::View::kFingersAway, 15.0}, Bound{synth::View::kHeadMounted, 40.0}}) {
    testing::OneHandRun run;
    int frames = 0;
    for (const uint64_t seed : kSeeds) {
      synth::SynthOptions options;
      options.motion = "pinch";
      options.view = b.view;
      options.seed = seed;
      options.arm = synth::Arm::kNone;
      run.add(testing::track_one_hand(options, shipped_config(), &testing::shipped_forest()));
      frames += options.frames;
    }
    std::printf("pinch %s without its arm: %.1f mm, %d of %d posed frames right\n",
                std::string(synth::view_name(b.view)).c_str(), run.mean_error_mm(), run.reported_as_shown, run.posed);
    EXPECT_GE(run.posed, frames * 99 / 100) << synth::view_name(b.view);
    EXPECT_LT(run.mean_error_mm(), b.max_mean_mm) << synth::view_name(b.view);
    EXPECT_GE(run.reported_as_shown, run.posed * 95 / 100) << synth::view_name(b.view);
  }
}


// A camera rolled about its optical axis (handtrack-synth --roll): the forearm enters from the
// image's left (90), top (180) or right (-90) instead of its bottom. Tracks `motion` of subject
// kSeeds[0] (150 frames) with `forest`, or with the rendered part labels where it is null; the
// mean fingertip error counts from frame kStarted.
struct RolledRun {
  testing::OneHandRun run;
  double started_mm = 0.0;
};
constexpr int kStarted = 60;  // fingercount's fist opens by frame 55
RolledRun track_rolled(const char* motion, double roll_deg, const PartForest* forest) {
  synth::SynthOptions options;
  options.motion = motion;
  options.seed = kSeeds[0];
  options.frames = 150;
  options.roll_deg = roll_deg;
  synth::SyntheticCamera camera(options);
  Tracker tracker(shipped_config());
  synth::SynthFrame frame;
  const FixedLabels rendered(&frame.labels.pixels);
  const PixelLabeller* labeller = forest != nullptr ? static_cast<const PixelLabeller*>(forest) : &rendered;
  RolledRun r;
  for (int i = 0; i < options.frames; ++i) {
    camera.render(i, frame);
    const TrackerOutput out = tracker.track(frame.depth, labeller);
    if (out.state == TrackingState::kNoHand) continue;
    ++r.run.posed;
    r.run.reported_as_shown += out.handedness == Handedness::kRight ? 1 : 0;
    if (i >= kStarted) r.run.error_sum_mm += testing::fingertip_error_mm(out, frame);
  }
  r.started_mm = r.run.error_sum_mm / (r.run.posed - kStarted);
  std::printf("%s rolled %+.0f deg, %s: frames %d-149 %.1f mm, %d of %d posed frames right\n", motion, roll_deg,
              forest != nullptr ? "the forest" : "rendered labels", kStarted, r.started_mm, r.run.reported_as_shown,
              r.run.posed);
  return r;
}

// Given the rendered part labels, segmentation, the (re)start search and the energy know no "up":
// such a hand is found in every frame, as the right hand, and tracked as the upright one once
// started (docs/TRACKER.md, "The forearm from any image edge"). Measured when written, seed 21,
// frames 60-149 at 0 / 90 / 180 / -90 deg: adbadd 3.7 / 3.8 / 3.8 / 3.9 mm, fingercount 4.8 / 4.8 /
// 4.9 / 5.0 mm. The start on fingercount's fist is not: over all 150 frames 8.0 / 12.1 / 8.0 / 8.1
// mm, the start at 90 deg 25-35 mm off where the upright one is 11-20, until the hand opens (frame
// 55).
TEST(HandFromAnyEdge, IsTrackedAsTheUprightHandGivenItsPartLabels) {
  for (const char* motion : {"adbadd", "fingercount"}) {
    const double upright_mm = track_rolled(motion, 0.0, nullptr).started_mm;
    for (const double roll : {90.0, 180.0, -90.0}) {
      const RolledRun rolled = track_rolled(motion, roll, nullptr);
      EXPECT_EQ(rolled.run.posed, 150) << motion << " rolled " << roll;
      EXPECT_GE(rolled.run.reported_as_shown, 147) << motion << " rolled " << roll;
      EXPECT_LT(rolled.started_mm, upright_mm + 1.0) << motion << " rolled " << roll;
    }
  }
}

// The shipped forest saw the motions upright only; it labels a rolled hand a second time with its
// probes turned by the nearest multiple of 45 deg to the hand's axis, and keeps those labels where
// its trees are surer of them (PartForestOptions::turned_readings; docs/FOREST.md, "A hand from
// another image edge"). Measured when written, frames 60-149 at 0 / 45 / 90 / 180 / -90 / -135
// deg: 4.0 / 3.7 / 3.9 / 3.7 / 4.0 / 3.9 mm, every frame right. Without the turned readings: 4.0 /
// 17.4 / 11.2 / 14.7 / 7.5 / 12.3 mm, and at 180, -90 and -135 deg the left hand in every frame.
TEST(HandFromAnyEdge, IsTrackedNearlyAsTheUprightHandWithTheShippedForest) {
  const PartForest& forest = testing::shipped_forest();
  const double upright_mm = track_rolled("adbadd", 0.0, &forest).started_mm;
  for (const double roll : {45.0, 90.0, 180.0, -90.0, -135.0}) {
    const RolledRun rolled = track_rolled("adbadd", roll, &forest);
    EXPECT_EQ(rolled.run.posed, 150) << "rolled " << roll;
    EXPECT_GE(rolled.run.reported_as_shown, 147) << "rolled " << roll;
    EXPECT_LT(rolled.started_mm, upright_mm + 1.0) << "rolled " << roll;
  }
}

}  // namespace
}  // namespace handtrack
