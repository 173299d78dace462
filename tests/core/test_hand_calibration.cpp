// The user-specific hand model of Sec. 6 (issue 4): synthetic subjects whose hands are shorter,
// longer, narrower or wider than the default model are tracked for a few frames with the default
// model, the scale is calibrated from those frames, and the result must be within 5 % of the
// subject's true length, width and sigma. (Whether the calibrated model then tracks better is
// measured in docs/TRACKER.md, not asserted: on these subjects even the true scale does not always
// track better than the default model.)
//
// The synthetic subject's `width` scales x coordinates and all radii (synth/hand_model.hpp), the
// tracker's width scales x and its sigma the Gaussians' radii: the true tracker scale of a subject
// (L, W) is {length L, width W, sigma W}.
#include "handtrack/core/hand_calibration.hpp"
#include "handtrack/synth/synthetic_camera.hpp"
#include "synthetic_tracking.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

namespace handtrack {
namespace {

constexpr double kTolerance = 0.05 + 1e-9;  // issue 4: "recovers a synthetic subject's scale within 5 %"
constexpr int kCalibrationFrames = 60;  // frames tracked with the default model before calibrating

synth::SyntheticCamera subject_camera(const synth::SubjectScale& subject, const char* motion) {
  synth::SynthOptions options;
  options.motion = motion;
  options.frames = kCalibrationFrames;
  options.seed = 11;
  options.subject = subject;
  return synth::SyntheticCamera(options);
}

struct Recovery {
  HandScale scale;
  double seconds = 0.0;
};

Recovery calibrate_subject(synth::SyntheticCamera& camera) {
  Tracker tracker(calibration_tracker_config());
  CalibrationSet set;
  synth::SynthFrame frame;
  for (int i = 0; i < kCalibrationFrames && !set.full(); ++i) {
    camera.render(i, frame);
    const auto out = tracker.track(frame.depth);
    set.offer(frame.depth, out, tracker.pose_tracker().hint());
  }
  const auto start = std::chrono::steady_clock::now();
  const auto result = calibrate_hand_scale(set.frames(), TrackerConfig{});
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  std::printf("  %d frames, %d grid points, score %.4f\n", set.size(), result.evaluations, result.score);
  return {result.scale, took.count()};
}

// What went wrong loading `text` as a profile ("" when it loaded).
std::string profile_error(const std::string& text) {
  const std::string file = ::testing::TempDir() + "/hand_profile_test.json";
  std::ofstream(file) << text;
  try {
    (void)load_hand_profile(file);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return {};
}

TEST(HandProfile, SavedProfileLoadsBack) {
  const std::string file = ::testing::TempDir() + "/hand_profile_roundtrip.json";
  save_hand_profile(file, HandScale{1.075, 0.925, 1.05});
  const auto s = load_hand_profile(file);
  EXPECT_DOUBLE_EQ(s.length, 1.075);
  EXPECT_DOUBLE_EQ(s.width, 0.925);
  EXPECT_DOUBLE_EQ(s.sigma, 1.05);
}

TEST(HandProfile, BadFilesGiveOneLineNamingFileAndField) {
  EXPECT_THROW((void)load_hand_profile("/nonexistent/profile.json"), std::runtime_error);
  const auto corrupt = profile_error("{\"hand_length\": 1.0,");
  EXPECT_NE(corrupt.find("hand_profile_test.json: not a JSON hand profile"), std::string::npos) << corrupt;
  const auto missing = profile_error(R"({"hand_length": 1.0, "hand_width": 1.0})");
  EXPECT_NE(missing.find("'gaussian_sigma' missing"), std::string::npos) << missing;
  const auto text = profile_error(R"({"hand_length": "long", "hand_width": 1.0, "gaussian_sigma": 1.0})");
  EXPECT_NE(text.find("'hand_length' missing or not a number"), std::string::npos) << text;
  const auto range = profile_error(R"({"hand_length": 1.0, "hand_width": 2.5, "gaussian_sigma": 1.0})");
  EXPECT_NE(range.find("'hand_width' must be within [0.5, 2], got 2.5"), std::string::npos) << range;
  EXPECT_NE(profile_error("[1, 2, 3]").find("JSON object"), std::string::npos);
  for (const auto& e : {corrupt, missing, text, range}) EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

// What calibrate_hand_scale throws for `frames` and `config` ("" when it does not).
std::string calibration_error(const std::vector<CalibrationFrame>& frames, const CalibrationConfig& config) {
  try {
    (void)calibrate_hand_scale(frames, TrackerConfig{}, config);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return {};
}

TEST(HandCalibration, NeedsFramesWithAHandAndASaneGrid) {
  EXPECT_NE(calibration_error({}, {}).find("no frames"), std::string::npos);
  const DepthInput empty;
  EXPECT_NE(calibration_error({{&empty, PoseParams::Zero()}}, {}).find("a frame without a hand"), std::string::npos);
  CalibrationConfig inverted;
  inverted.lo = 1.2;
  EXPECT_NE(calibration_error({}, inverted).find("the grid needs"), std::string::npos);
}

TEST(HandCalibration, RecoversSyntheticSubjectsScale) {
  const synth::SubjectScale subjects[] = {{1.0, 1.0}, {0.9, 1.0}, {1.1, 1.0}, {1.0, 0.92}, {1.0, 1.08}, {0.9, 0.92}, {1.1, 1.08}};
  std::printf("true L,W      recovered L,W,S      time s\n");
  for (const auto& subject : subjects) {
    auto camera = subject_camera(subject, "adbadd");
    const auto r = calibrate_subject(camera);
    std::printf("%.2f,%.2f    %.3f,%.3f,%.3f    %.2f\n", subject.length, subject.width, r.scale.length, r.scale.width,
                r.scale.sigma, r.seconds);
    EXPECT_NEAR(r.scale.length, subject.length, kTolerance * subject.length);
    EXPECT_NEAR(r.scale.width, subject.width, kTolerance * subject.width);
    EXPECT_NEAR(r.scale.sigma, subject.width, kTolerance * subject.width);
  }
}

// Self-calibration (TrackerConfig::self_calibrate, core/src/self_calibration.hpp): a hand 15 % smaller
// than the default model, tracked by a Tracker as handtrackd tracks (no profile, no offline step).
struct Tracked {
  HandScale scale;           // the tracker's after the last frame
  HandScale reported;        // TrackerOutput::scale of the last frame
  double late_error_mm = 0;  // mean fingertip error over the second half of the frames
  HandScale in_trial;        // TrackerOutput::scale of one more frame, in a handedness trial
};

Tracked track_subject(const synth::SubjectScale& subject, synth::View view, TrackerConfig config,
                      const char* motion = "adbadd") {
  synth::SynthOptions options;
  options.motion = motion;
  options.view = view;
  options.frames = 160;
  options.seed = 11;
  options.subject = subject;
  synth::SyntheticCamera camera(options);
  Tracker tracker(config);
  synth::SynthFrame frame;
  Tracked t;
  int scored = 0;
  for (int i = 0; i < options.frames; ++i) {
    camera.render(i, frame);
    const auto out = tracker.track(frame.depth, &testing::shipped_forest());
    tracker.wait_for_checks();  // background: as if the camera waited for the idle CPU
    t.reported = out.scale;
    if (i < options.frames / 2 || out.state == TrackingState::kNoHand) continue;
    for (int f = 0; f < kNumFingers; ++f) {
      t.late_error_mm += (out.fingertips[static_cast<size_t>(f)] - *frame.fingertips[static_cast<size_t>(f)]).norm();
    }
    scored += kNumFingers;
  }
  t.scale = tracker.config().scale;
  t.late_error_mm = scored > 0 ? t.late_error_mm / scored : 1e9;
  tracker.question_handedness();  // both hands from the next frame on, as at a (re)start
  t.in_trial = tracker.track(frame.depth, &testing::shipped_forest()).scale;
  return t;
}

// The scale self-calibration finds: the subject's (L, W) is the tracker's {L, W, W} (above).
void expect_scale_of(const HandScale& found, const synth::SubjectScale& subject) {
  EXPECT_NEAR(found.length, subject.length, kTolerance * subject.length);
  EXPECT_NEAR(found.width, subject.width, kTolerance * subject.width);
  EXPECT_NEAR(found.sigma, subject.width, kTolerance * subject.width);
}

constexpr synth::SubjectScale kSmallHand{0.85, 0.85};

// The shipped configuration: late fusion with the shipped forest.
TrackerConfig shipped(bool self_calibrate) {
  TrackerConfig config = testing::paper_config(EnergyMode::kLateFusion);
  config.self_calibrate = self_calibrate;
  return config;
}

TEST(SelfCalibration, ASmallHandIsTrackedWithItsOwnScaleAndBetter) {
  const Tracked before = track_subject(kSmallHand, synth::View::kPalm, shipped(false));
  const Tracked after = track_subject(kSmallHand, synth::View::kPalm, shipped(true));
  std::printf("  fixed scale %.2f mm, calibrated to %.3f,%.3f,%.3f: %.2f mm\n", before.late_error_mm,
              after.scale.length, after.scale.width, after.scale.sigma, after.late_error_mm);
  EXPECT_EQ(before.scale, HandScale{});
  expect_scale_of(after.scale, kSmallHand);
  EXPECT_EQ(after.reported, after.scale);  // what the ring's hand_scale carries
  // Measured: 17.6 -> 13.2 mm (15.1 with the length alone, as shipped until 2026-11-30).
  EXPECT_LT(after.late_error_mm, before.late_error_mm - 3.0);
  // A handedness trial fits both hands with the length found but the configured width and sigma
  // (Tracker::use_calibrated_model). Mutation check, the trial given the calibrated model too: fails.
  EXPECT_EQ(after.in_trial.length, after.scale.length);
  EXPECT_EQ(after.in_trial.width, 1.0);
  EXPECT_EQ(after.in_trial.sigma, 1.0);
}

TEST(SelfCalibration, RunsInTheBackgroundAsHandtrackdRunsIt) {
  TrackerConfig config = shipped(true);
  config.background_checks = true;
  const Tracked t = track_subject(kSmallHand, synth::View::kPalm, config);
  // With checks in the background this flat hand is still in its first handedness trial at the
  // end (a palm and the other hand's back explain it alike, and the trial goes on until the
  // evidence is clear), so it is fitted with the trial's model: the length found, the configured
  // width and sigma (the synchronous test above sees the whole scale once its trial has ended).
  EXPECT_NEAR(t.scale.length, kSmallHand.length, kTolerance * kSmallHand.length);
  EXPECT_EQ(t.reported, t.scale);
}

// A hand seen edge-on shows its length but not its width: its frames are not calibrated on, and the
// scale stays (calibrated on every tracked frame, the side view found widths at the bottom of the
// search's range).
TEST(SelfCalibration, AHandSeenEdgeOnKeepsItsScale) {
  const Tracked t = track_subject(kSmallHand, synth::View::kSide, shipped(true));
  EXPECT_EQ(t.scale, HandScale{});
}

}  // namespace
}  // namespace handtrack
