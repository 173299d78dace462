// A body in the working volume (core/src/body_eraser.hpp): real SR305 frames (../shared/data,
// skipped where absent) of a user turned toward the camera with a raised right hand, in the working
// volume a hand at 550-650 mm needs (far 900 mm): the user's shoulder, torso and head are as near
// as the hand. Each frame is held still for 20 frames and tracked by HandsTracker in the shipped
// configuration (late fusion, the shipped forest), as handtrackd would track a user standing still.
//
// Measured (docs/TRACKER.md, "Real frames"): before the body eraser, in 231615/200 the hand was
// never found, with room for one hand or two (the torso, nearer by its mean depth, was taken for it,
// or its head with two); now it is, in 20 of 20 frames with two, and 19 of 20 with one (the first
// frame tries a fragment of the body nearer than the hand, which fits no hand). What is
// not fixed and not asserted: with two, the head or a fragment of the body is fitted as a second
// hand in most frames (confidence 0.65-0.86, as high as a real hand's).
#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/png_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace handtrack {
namespace {

namespace fs = std::filesystem;

// The hand is at the image's left (u < 380), the body right of it.
constexpr double kHandUMax = 380.0;

// How many of `frames` repeats of the frame report a hand at the raised hand's place.
int frames_with_the_hand(const DepthImage& depth, int max_hands, int frames) {
  static const PartForest forest = PartForest::load(shipped_forest_path().value());
  TrackerConfig config;
  config.input.far_mm = 900.0;
  config.mode = EnergyMode::kLateFusion;
  config.max_hands = max_hands;
  HandsTracker tracker(config);
  int with_hand = 0;
  for (int f = 0; f < frames; ++f) {
    const HandsOutput out = tracker.track(depth, &forest);
    bool hand = false;
    for (int k = 0; k < out.count; ++k) {
      hand = hand || depth.camera.project(out.hands[static_cast<size_t>(k)].palm_centre).x() < kHandUMax;
    }
    with_hand += hand ? 1 : 0;
  }
  return with_hand;
}

TEST(BodyInView, TheRaisedHandIsFoundBesideABodyAsNearAsIt) {
  const fs::path dir = fs::path(HANDTRACK_SHARED_DATA_DIR) / "real-sr305" / "20210326-231615";
  if (!fs::exists(dir)) GTEST_SKIP() << "shared data absent: " << dir;
  const CameraIntrinsics cam{Sr305Camera::kWidth, Sr305Camera::kHeight, Sr305Camera::kFx, Sr305Camera::kFy,
                             Sr305Camera::kCx,    Sr305Camera::kCy,     Sr305Camera::kDepthScaleMm, 30};
  for (const char* name : {"160.png", "200.png", "220.png"}) {
    SCOPED_TRACE(name);
    const auto raw = read_png_gray16(dir / name);
    const DepthImage depth = DepthImage::from_raw(cam, raw.pixels);
    EXPECT_GE(frames_with_the_hand(depth, 2, 20), 18);
  }
  // With room for one hand: a surface whose (re)start found no hand is passed over for the next.
  const auto raw = read_png_gray16(dir / "200.png");
  EXPECT_GE(frames_with_the_hand(DepthImage::from_raw(cam, raw.pixels), 1, 20), 15);
}

}  // namespace
}  // namespace handtrack
