// Left and right hands (Tracker with HandednessMode::kAuto): a left hand is tracked as the right
// hand of the mirrored image, and the hand is chosen by the fits' evidence over the frames of a
// trial after every (re)start (Tracker::weigh).
// - Synthetic left and right hands (the exact mirror image, synth --hand left): tracked as well as
//   each other, each reported as its own hand.
// - Real SR305 frames (right hands; ../shared/data, skipped where absent): the same frame mirrored
//   left to right (image and cx) always fits as the other hand, with fingertips that are the
//   mirror of the first fit's; and most frames fit as the right hand they are, also held still
//   (shown trembling by a pixel). Not all: a palm-facing right hand explains about as much of the
//   depth as a left hand seen from the back (a model of isotropic Gaussians is nearly the same seen
//   from either side), and the forest, trained on renders, labels real fingers poorly, so which
//   hand a real frame ends as turns even on the alignment of the pixel grid: the failure the issue
//   "Every hand, every view" still has to remove.
#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/png_io.hpp"
#include "handtrack/core/tracker.hpp"
#include "handtrack/synth/synthetic_camera.hpp"
#include "handtrack/synth/views.hpp"
#include "synthetic_tracking.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

namespace handtrack {
namespace {

namespace fs = std::filesystem;

testing::OneHandRun track_synthetic(const std::string& motion, synth::Handedness hand, uint64_t seed) {
  synth::SynthOptions options;
  options.motion = motion;
  options.frames = 120;
  options.seed = seed;
  options.hand = hand;
  return testing::track_one_hand(options, TrackerConfig{});
}

using HandCase = std::tuple<std::string, synth::Handedness, uint64_t>;
class SyntheticHands : public ::testing::TestWithParam<HandCase> {};

std::string case_name(const ::testing::TestParamInfo<HandCase>& c) {
  return std::get<0>(c.param) + "_" + std::string(synth::handedness_name(std::get<1>(c.param)));
}

TEST_P(SyntheticHands, TrackedAndReportedAsTheHandTheyAre) {
  const auto& [motion, hand, seed] = GetParam();
  const testing::OneHandRun run = track_synthetic(motion, hand, seed);
  EXPECT_GE(run.posed, 114) << "a pose in at least 95 % of the frames";
  EXPECT_LE(run.mean_error_mm(), 12.0);
  EXPECT_GE(run.reported_as_shown, static_cast<int>(0.98 * run.posed))
      << run.reported_as_shown << " of " << run.posed << " frames reported as the " << synth::handedness_name(hand)
      << " hand";
}

INSTANTIATE_TEST_SUITE_P(
    LeftAndRight, SyntheticHands,
    ::testing::Values(std::make_tuple("pinch", synth::Handedness::kRight, 11), std::make_tuple("pinch", synth::Handedness::kLeft, 11),
                      std::make_tuple("fingerwave", synth::Handedness::kLeft, 12),
                      std::make_tuple("adbadd", synth::Handedness::kLeft, 13)),
    case_name);

// The SR305's frames of both recordings, fitted from scratch with the working volume these
// recordings need (docs/TRACKER.md, "Real frames"), depth-only and in the shipped configuration
// (late fusion with the shipped forest). Measured on the 17 frames with a hand in the volume
// (2026-11-27): depth-only all but 231615/160 fit as a right hand, with late fusion all 17; most of
// them by the tie rule (the evidence within the tie: docs/TRACKER.md, "E_sim's coverage cap"), so a
// change to the model or the energy turns one or two easily (an earlier version: with late fusion
// all but 230536/30, 90, 130 and 150; since the forest of 15,000 images and the once-split partial
// leaves, 2026-11-28, all but 230536/170 and 231615/100, 200; and the same frame moved by one pixel
// turns others: docs/TRACKER.md, "Real frames"). Since the labels choose only among fits that
// explain the depth about as well as the best (2026-11-30): with late fusion all of them, depth-only
// all but 231615/200. The bound: 3 of 4 depth-only, 11 of 12 with late fusion (2 of 3 before); the
// issue's goal is every frame.
struct RealCase {
  EnergyMode mode;
  int min_right_hands_of_12;  // of every 12 frames with a hand, at least this many right hands
};
class RealHands : public ::testing::TestWithParam<RealCase> {};

const fs::path kSr305Root = fs::path(HANDTRACK_SHARED_DATA_DIR) / "real-sr305";

// The depth frames of both SR305 recordings, sorted; empty where the shared data is absent.
std::vector<fs::path> sr305_frames() {
  std::vector<fs::path> files;
  for (const char* recording : {"20210326-230536", "20210326-231615"}) {
    if (!fs::exists(kSr305Root / recording)) return {};
    for (const auto& entry : fs::directory_iterator(kSr305Root / recording)) {
      if (entry.path().extension() == ".png") files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

DepthImage read_sr305_frame(const fs::path& file) {
  const CameraIntrinsics cam{Sr305Camera::kWidth, Sr305Camera::kHeight, Sr305Camera::kFx, Sr305Camera::kFy,
                             Sr305Camera::kCx,    Sr305Camera::kCy,     Sr305Camera::kDepthScaleMm, 30};
  return DepthImage::from_raw(cam, read_png_gray16(file).pixels);
}

std::string sr305_name(const fs::path& file) {
  return file.parent_path().filename().string() + "/" + file.filename().string();
}

// The configuration these recordings need (docs/TRACKER.md, "Real frames"): hands to 800 mm.
TrackerConfig sr305_config(EnergyMode mode) {
  TrackerConfig config;
  config.input.far_mm = 800.0;
  config.mode = mode;
  return config;
}

TEST_P(RealHands, Sr305FramesAreRightHandsAndTheirMirrorImagesTheOtherHand) {
  const std::vector<fs::path> files = sr305_frames();
  if (files.empty()) GTEST_SKIP() << "shared data absent: " << kSr305Root;
  const TrackerConfig config = sr305_config(GetParam().mode);
  const PixelLabeller* labeller = config.mode == EnergyMode::kLateFusion ? &testing::shipped_forest() : nullptr;
  int frames = 0;
  int right_hands = 0;
  for (const fs::path& file : files) {
    const DepthImage depth = read_sr305_frame(file);
    const CameraIntrinsics& cam = depth.camera;
    DepthImage mirrored = depth;
    mirrored.camera.cx = static_cast<double>(cam.width - 1) - cam.cx;
    for (int v = 0; v < cam.height; ++v) {
      const auto row = mirrored.depth_mm.begin() + static_cast<std::ptrdiff_t>(v) * cam.width;
      std::reverse(row, row + cam.width);
    }
    Tracker as_seen(config);
    Tracker as_mirrored(config);
    const TrackerOutput right = as_seen.track(depth, labeller);
    const TrackerOutput left = as_mirrored.track(mirrored, labeller);
    const std::string name = sr305_name(file);
    if (right.state == TrackingState::kNoHand) continue;  // beyond the working volume: nothing to say
    ++frames;
    right_hands += right.handedness == Handedness::kRight ? 1 : 0;
    if (right.handedness != Handedness::kRight) std::cout << "fits as a left hand: " << name << "\n";
    EXPECT_NE(left.handedness, right.handedness) << name << ": the mirror image is the other hand";
    for (size_t t = 0; t < 5; ++t) {
      const Eigen::Vector3d mirror_of_right(-right.fingertips[t].x(), right.fingertips[t].y(), right.fingertips[t].z());
      EXPECT_LT((left.fingertips[t] - mirror_of_right).norm(), 10.0) << name << " fingertip " << t;
    }
  }
  EXPECT_GE(frames, 6) << "frames with a hand in the working volume";
  EXPECT_GE(12 * right_hands, GetParam().min_right_hands_of_12 * frames)
      << right_hands << " of " << frames << " frames fit as a right hand";
}

INSTANTIATE_TEST_SUITE_P(DepthOnlyAndShipped, RealHands,
                         ::testing::Values(RealCase{EnergyMode::kDepthOnly, 9}, RealCase{EnergyMode::kLateFusion, 11}),
                         [](const ::testing::TestParamInfo<RealCase>& c) {
                           return std::string(c.param.mode == EnergyMode::kLateFusion ? "late_fusion" : "depth_only");
                         });

// A real hand the forest mislabels: in SR305 frame 230536/130 (an open right hand, its fingers
// toward the image's right, the thumb down) the forest calls most of the fingers "palm". A
// right-hand tracker's (re)start search must still fit the model's fingers on the fingers, as
// the depth says, not bunch them over the palm where the labels agree with them: the fit the
// search keeps explains at least 0.9 of the hand. Before the labels chose only among fits that
// explain the depth about as well as the best (start_search.cpp, kLabelChoiceLead), it chose one
// with its fingers bunched over the palm: confidence 0.61, label agreement 0.68, against 0.97 and
// 0.35 for the fit on the fingers, which was not refined at all (fourth by score after screening).
TEST(RealHandStart, AHandTheForestMislabelsIsFittedAsTheDepthShowsIt) {
  const fs::path file = kSr305Root / "20210326-230536" / "130.png";
  if (!fs::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  TrackerConfig config = sr305_config(EnergyMode::kLateFusion);
  config.handedness = HandednessMode::kRight;
  Tracker tracker(config);
  const TrackerOutput out = tracker.track(read_sr305_frame(file), &testing::shipped_forest());
  ASSERT_NE(out.state, TrackingState::kNoHand);
  EXPECT_GE(out.confidence, 0.9) << "label agreement " << out.label_agreement;
  EXPECT_LT(out.palm_normal.z(), 0.0) << "the palm faces the camera";
}

// Each SR305 frame shown kStillShown times in a row to a fresh tracker (`shown(frames)`: the hand
// it reports at the end of the frames, nullopt for none): how many frames had a hand in the
// working volume, and how many of them were the right hand at the end. The others are printed.
//
// Shown trembling: frame k is the recorded image moved by (0, 0), (1, 0), (1, 1) or (0, 1) pixels
// in turn, the camera unchanged, a hand that moves by a pixel (about 1.5 mm at 700 mm) from frame
// to frame, as a real hand held still does. The same image shown unchanged 31 times turns on the
// alignment of the pixel grid alone: moved by one pixel with the principal point moved with it
// (the same scene in 3D), the share of these frames reported right went from 90 % to 60-84 %
// (scripts/eval-real-still, docs/TRACKER.md "Real frames"), so a bound on the unchanged image
// asserts one lucky alignment.
constexpr int kStillShown = 31;
struct StillFrames {
  int frames = 0;
  int right = 0;
};

// `depth` moved by (dx, dy) >= 0 pixels; the uncovered border has no depth.
DepthImage moved(const DepthImage& depth, int dx, int dy) {
  DepthImage out = depth;
  std::fill(out.depth_mm.begin(), out.depth_mm.end(), 0.0F);
  for (int v = dy; v < depth.height(); ++v) {
    for (int u = dx; u < depth.width(); ++u) out.at(u, v) = depth.at(u - dx, v - dy);
  }
  return out;
}

std::vector<DepthImage> trembling(const DepthImage& depth) {
  const std::array<DepthImage, 4> aligned = {depth, moved(depth, 1, 0), moved(depth, 1, 1), moved(depth, 0, 1)};
  std::vector<DepthImage> frames;
  for (int k = 0; k < kStillShown; ++k) frames.push_back(aligned[static_cast<size_t>(k % 4)]);
  return frames;
}

template <typename Shown>
StillFrames still_frames(const std::vector<fs::path>& files, Shown&& shown) {
  StillFrames count;
  for (const fs::path& file : files) {
    const std::optional<Handedness> hand = shown(trembling(read_sr305_frame(file)));
    if (!hand) continue;  // beyond the working volume
    ++count.frames;
    count.right += *hand == Handedness::kRight ? 1 : 0;
    if (*hand != Handedness::kRight) std::cout << "a left hand at the end: " << sr305_name(file) << "\n";
  }
  return count;
}

// A real hand held still: each SR305 frame shown trembling to one tracker (a (re)start, its
// handedness trial, then tracking, with the trials again of a mediocre fit) is still reported as
// the right hand it is at the end, in the shipped configuration. Measured (2026-11-28, seed 1): 16
// of the 19 frames (230536/170 and 231615/100, 200 left); with the forest of 5,000 images and
// the partial leaves not split, 15 (230536/130, 150, 170 and 231615/180 left), with E_sim's
// coverage cap and without it alike. (On the unchanged image, 17 of 17 with the cap and 14 of 17
// without, but that alignment's luck: docs/TRACKER.md, "Real frames".) Since the labels choose only
// among fits that explain the depth about as well as the best (2026-11-30), all but 231615/200
// (230536/130 was left before it). The bound: 3 of 4.
TEST(RealStillHand, StaysTheRightHandWhileTracked) {
  const std::vector<fs::path> files = sr305_frames();
  if (files.empty()) GTEST_SKIP() << "shared data absent: " << kSr305Root;
  const PartForest& forest = testing::shipped_forest();
  const StillFrames still = still_frames(files, [&](const std::vector<DepthImage>& frames) -> std::optional<Handedness> {
    Tracker tracker(sr305_config(EnergyMode::kLateFusion));
    TrackerOutput out;
    for (const DepthImage& depth : frames) out = tracker.track(depth, &forest);
    if (out.state == TrackingState::kNoHand) return std::nullopt;
    return out.handedness;
  });
  EXPECT_GE(still.frames, 6) << "frames with a hand in the working volume";
  EXPECT_GE(4 * still.right, 3 * still.frames) << still.right << " of " << still.frames
                                               << " still frames stayed a right hand";
}

// The same still frames as handtrackd tracks them: HandsTracker with room for one hand (the frame
// shared out first), the last of the trembling frames. Measured (2026-11-28, seed 1): 16 of 19
// (230536/170 and 231615/100, 180 left; in 230536/170 the hand, arm and body are near one another);
// with the forest of 5,000 images and the partial leaves not split, 15 (230536/150, 170 and
// 231615/20, 200 left; 231615/20's thumb labelled a little finger). Since the labels choose only
// among fits that explain the depth about as well as the best (2026-11-30), 17 of 19 (231615/180,
// 200 left; 230536/130 was left before it). The goal, every frame right, is not met; the
// bound (3 of 4) guards what is.
TEST(RealStillHand, MostStayTheRightHandAsHandtrackdTracksThem) {
  const std::vector<fs::path> files = sr305_frames();
  if (files.empty()) GTEST_SKIP() << "shared data absent: " << kSr305Root;
  const PartForest& forest = testing::shipped_forest();
  TrackerConfig config = sr305_config(EnergyMode::kLateFusion);
  config.max_hands = 1;
  const StillFrames still = still_frames(files, [&](const std::vector<DepthImage>& frames) -> std::optional<Handedness> {
    HandsTracker tracker(config);
    HandsOutput out;
    for (const DepthImage& depth : frames) out = tracker.track(depth, &forest);
    if (out.count == 0) return std::nullopt;
    return out.hands[0].handedness;
  });
  EXPECT_GE(still.frames, 15) << "frames with a hand in the working volume";
  EXPECT_GE(4 * still.right, 3 * still.frames) << still.right << " of " << still.frames
                                               << " still frames reported as the right hand";
}

// A right-hand sequence of scripts/eval-synthetic: `motion` in `view`, subject `seed`, 300 frames,
// over the background handtrack-synth gives that view.
synth::SynthOptions benchmark_sequence(const std::string& motion, synth::View view, uint64_t seed) {
  synth::SynthOptions options;
  options.motion = motion;
  options.view = view;
  options.background = synth::default_background(motion, view);
  options.hand = synth::Handedness::kRight;
  options.frames = testing::kSequenceFrames;
  options.seed = seed;
  return options;
}

// `options` tracked with late fusion as `config` says from frame 0, scored from `from_frame` on.
testing::OneHandRun track_late_fusion(const synth::SynthOptions& options, TrackerConfig config, int from_frame = 0) {
  config.mode = EnergyMode::kLateFusion;
  return testing::track_one_hand(options, config, &testing::shipped_forest(), from_frame);
}

double share_as_shown(const testing::OneHandRun& run) {
  return run.posed > 0 ? static_cast<double>(run.reported_as_shown) / run.posed : 0.0;
}

// A hand taken for the wrong hand on a fist (fingercount starts as one, which either hand
// explains), whose fit stays mediocre, is tried as the other hand again
// (TrackerConfig::handedness_recheck_frames): the shipped configuration reports the hand shown in
// the second half of the sequence. Without those trials it never does, which this test also
// checks, so that it keeps exercising them. The wrong choice is made for it: a tracker told the
// hand is a left one fits fingercount's fist (seen fingers toward, subject 1, a right hand) for
// the first 30 frames, and the tracker under test resumes from that (Tracker::resume), as if its
// first trial had chosen so. Its scene until 2026-11-29 chose wrong by itself; the tipped fists of
// the (re)start search now start it right, and of the benchmark's sequences (seven motions, six
// views, seeds 1-6, right hands; five motions, left hands and the paper's w_s) none but the flat
// hand's tie (HandednessTie below) ends its first trial wrong and stays wrong without the trials
// again (docs/TRACKER.md, "A fist at a (re)start").
TEST(HandednessRetrial, AHandTakenForTheWrongHandOnAFistIsTriedAgain) {
  const synth::SynthOptions options = benchmark_sequence("fingercount", synth::View::kFingersToward, 1);
  constexpr int kChosenWrongFrames = 30;
  const auto share_right_from_150 = [&](const TrackerConfig& config) {
    synth::SyntheticCamera camera(options);
    synth::SynthFrame frame;
    TrackerConfig as_left = config;
    as_left.handedness = HandednessMode::kLeft;
    Tracker chosen_wrong(as_left);
    TrackerOutput out;
    for (int i = 0; i < kChosenWrongFrames; ++i) {
      camera.render(i, frame);
      out = chosen_wrong.track(frame.depth, &testing::shipped_forest());
    }
    EXPECT_EQ(out.handedness, Handedness::kLeft);
    Tracker tracker(config);
    tracker.resume(out);
    int posed = 0;
    int right = 0;
    for (int i = kChosenWrongFrames; i < options.frames; ++i) {
      camera.render(i, frame);
      const TrackerOutput now = tracker.track(frame.depth, &testing::shipped_forest());
      if (i < 150 || now.state == TrackingState::kNoHand) continue;
      ++posed;
      right += now.handedness == Handedness::kRight ? 1 : 0;
    }
    return posed > 0 ? static_cast<double>(right) / posed : 0.0;
  };
  TrackerConfig config;
  config.mode = EnergyMode::kLateFusion;
  TrackerConfig without = config;
  without.handedness_recheck_frames = 0;
  const double with_share = share_right_from_150(config);
  const double without_share = share_right_from_150(without);
  std::printf("frames 150-299 reported as the right hand: %.2f with trials again, %.2f without\n", with_share,
              without_share);
  EXPECT_GE(with_share, 0.9);
  EXPECT_LE(without_share, 0.5) << "the hand taken for the wrong hand no longer stays wrong without the trials "
                                   "again: this scene no longer tests them";
}

// A flat hand seen from the back (adbadd in the back view, subject 7, as in scripts/eval-synthetic):
// its right-hand fit and the left hand's mirror image with the palm toward the camera explain the
// depth alike, and its first trial's evidence is a tie. What the depth leaves open, the camera's
// arrangement decides (TrackerConfig::arrangement, Tracker::weigh): a camera facing the user
// expects the palm, and reports this hand as a left hand (throughout until 2026-12-02); a
// head-mounted camera expects the back, and reports the right hand. (Subject 3 was this scene until
// the surface fronts, 2026-11-29, which tell its side in 19 % of the frames; of subjects 1-9 only 7
// is still a tie.) Since the palm's hollow is weighed (palm_hollow.hpp), the renderer's flat hand
// reads 0.1-1.5 mm convex from behind, a little evidence for its back: the first frame's tie still
// goes to the palm, and the trial, whose evidence never leaves the margin, passes the tie on frame
// 249 and turns the last 52 of the 300 frames to the right hand (17 %; the bound: 25 %).
TEST(HandednessTie, AFlatHandShowsTheSideItsCamerasArrangementExpects) {
  const synth::SynthOptions options = benchmark_sequence("adbadd", synth::View::kBack, 7);
  const auto share_right = [&](CameraArrangement arrangement) {
    TrackerConfig config;
    config.arrangement = arrangement;
    const testing::OneHandRun run = track_late_fusion(options, config);
    std::printf("%s: %d of %d frames reported as the right hand, %.1f mm\n", to_string(arrangement),
                run.reported_as_shown, run.posed, run.mean_error_mm());
    EXPECT_LE(run.mean_error_mm(), 12.0) << to_string(arrangement) << ": either hand fits this flat hand";
    return share_as_shown(run);
  };
  EXPECT_GE(share_right(CameraArrangement::kHeadMounted), 0.95);
  EXPECT_LE(share_right(CameraArrangement::kFacing), 0.25)
      << "the depth now tells this hand's side: this scene no longer tests the arrangement";
}

// A flat hand whose back is convex, as a real hand's is (handtrack-synth --palm-arch 8
// --palm-arch-shape back: the back of the hand arched across the knuckles by 8 mm, its palm flat),
// seen from the back (adbadd, subject 2): the right hand's fit and the left hand's palm-toward mirror
// image explain it alike (confidence 0.91 against 0.90), and before the palm's hollow was weighed the
// first frame's tie went to the palm toward a desk camera: the wrong hand throughout, the right hand
// and its mirror image, the left hand, alike (0 % right, 2026-12-02). The depth's convexity across
// the palm (palm_hollow.hpp) tells the back: each is the hand it is in nearly every frame.
TEST(HandednessHollow, AConvexBackSeenFromBehindIsTheHandItIs) {
  for (const synth::Handedness hand : {synth::Handedness::kRight, synth::Handedness::kLeft}) {
    synth::SynthOptions options = benchmark_sequence("adbadd", synth::View::kBack, 2);
    options.hand = hand;
    options.palm_arch_mm = 8.0;
    options.palm_arch = synth::PalmArch::kBack;
    const testing::OneHandRun run = track_late_fusion(options, TrackerConfig{});
    std::printf("%s hand: %d of %d frames reported as the hand shown, %.1f mm\n",
                hand == synth::Handedness::kRight ? "right" : "left", run.reported_as_shown, run.posed,
                run.mean_error_mm());
    EXPECT_GE(share_as_shown(run), 0.95) << (hand == synth::Handedness::kRight ? "right" : "left") << " hand";
  }
}

// A fist seen from behind (fingercount in the head-mounted view, subject 5, as in
// scripts/eval-synthetic): on the trial's first five frames the right hand's (re)start finds nothing
// while the left hand's finds a fit. Those frames, weighed in full, chose the left hand, kept for a
// third of the sequence (68 % right). A hand whose search has found nothing yet in a trial is no
// evidence either way (Tracker::weigh): on those frames the left hand's fit is reported with no
// evidence at all (handedness confidence 0), where weighing them would have put it at 0.45-0.64,
// the left fit's score. (Subject 8 was this scene before the knuckles, 2026-11-29, which found its right
// hand at once.) The whole sequence was the right hand in 98 % of its frames until the fists seen
// from behind, 2026-11-29, last; since, 77 %: the right hand's fit, found on frame 5, trails the
// left's by 0.06 in the label agreement of frame 6, which starts the evidence, and the trial keeps
// the left hand to frame 68 (docs/TRACKER.md, "Fists seen from behind").
TEST(HandednessTrial, AHandWhoseStartFoundNothingYetIsNotOutvotedByIt) {
  constexpr int kRightHandNotFoundFrames = 5;
  synth::SyntheticCamera camera(benchmark_sequence("fingercount", synth::View::kHeadMounted, 5));
  TrackerConfig config;
  config.mode = EnergyMode::kLateFusion;
  Tracker tracker(config);
  synth::SynthFrame frame;
  for (int i = 0; i < kRightHandNotFoundFrames; ++i) {
    camera.render(i, frame);
    const TrackerOutput out = tracker.track(frame.depth, &testing::shipped_forest());
    ASSERT_NE(out.state, TrackingState::kNoHand) << "frame " << i << ": the left hand's fit is reported";
    EXPECT_EQ(out.handedness_confidence, 0.0)
        << "frame " << i << ": a trial with one hand not yet found has no evidence";
  }
  // The right hand (re)started again on the trial's fifth frame and found: from then on the two
  // fits are evidence.
  TrackerOutput out;
  for (int i = kRightHandNotFoundFrames; i < kRightHandNotFoundFrames + 3; ++i) {
    camera.render(i, frame);
    out = tracker.track(frame.depth, &testing::shipped_forest());
  }
  EXPECT_GT(out.handedness_confidence, 0.0);
}

// A trial fits both hands, and a hand lost in it (its start found nothing) is not started again
// while checks are off the frame (spread, or in the background: handtrackd's default); its input
// is not built either (Tracker::request). In random's subject 1 (handtrack-bench's motion) the left
// hand's start on the first frame finds nothing: the 29 frames of the trial that follow each built
// both hands' inputs and fitted one, about twice the preprocessing (docs/BENCHMARKS.md). (The
// bench's own subject, 7, was such a scene until the knuckles, 2026-11-29; of random's subjects
// 1-30 seven still are.)
TEST(HandednessTrial, ALostHandIsNotPreprocessed) {
  synth::SynthOptions options;
  options.motion = "random";
  options.frames = 31;
  options.seed = 1;
  synth::SyntheticCamera camera(options);
  TrackerConfig config;
  config.mode = EnergyMode::kDepthOnly;
  config.particles = 2;
  config.optimizer.iterations = 10;
  config.check_iterations_per_frame = 64;
  Tracker tracker(config);
  const int one_hand = config.particles * config.optimizer.iterations;
  int trial_frames_one_input = 0;
  for (int i = 0; i < options.frames; ++i) {
    const InputRequest request = tracker.request();
    const TrackerOutput out = tracker.track(camera.render(i).depth);
    ASSERT_NE(out.state, TrackingState::kNoHand) << "frame " << i;
    if (request.right && request.left) {
      EXPECT_GE(out.iterations, 2 * one_hand) << "frame " << i << ": both hands preprocessed, one fitted";
    } else if (i > 0 && i < config.handedness_trial_frames) {
      ++trial_frames_one_input;
    }
  }
  EXPECT_GT(trial_frames_one_input, 0) << "no hand was lost in the first trial: this scene no longer tests it";
}

}  // namespace
}  // namespace handtrack
