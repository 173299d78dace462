// The pinch-to-click example's hysteresis (clients/examples/pinch_detector.hpp): what a user of
// the HCI example notices is one click per pinch, not a burst of clicks from tracking jitter.
#include "pinch_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

using handtrack::examples::PinchDetector;
using handtrack::examples::PinchEvent;

namespace {

// Feeds distances (strength 0) and returns the events as 'S'/'E' characters.
std::string run(PinchDetector& detector, const std::vector<float>& distances_mm) {
  std::string events;
  for (float d : distances_mm) {
    const PinchEvent e = detector.update(true, d, 0.0F);
    if (e == PinchEvent::kStart) events += 'S';
    if (e == PinchEvent::kEnd) events += 'E';
  }
  return events;
}

}  // namespace

TEST(PinchDetector, OnePinchIsOneStartAndOneEnd) {
  PinchDetector detector;
  EXPECT_EQ(run(detector, {80, 60, 40, 20, 12, 8, 10, 14, 25, 45, 70}), "SE");
  EXPECT_FALSE(detector.pinching());
}

TEST(PinchDetector, JitterAroundEitherThresholdDoesNotClickAgain) {
  PinchDetector detector;
  // Hovering around 15 mm (start) then around 30 mm (end): the band between holds the state.
  EXPECT_EQ(run(detector, {16, 14.9F, 16, 14, 17, 20, 29, 31, 29, 33, 28, 40}), "SE");
  // Approaching to 16-29 mm never starts a pinch.
  EXPECT_EQ(run(detector, {40, 29, 20, 16, 18, 25, 35}), "");
}

TEST(PinchDetector, StrengthStartsAndMustAlsoReleaseToEnd) {
  PinchDetector detector;
  EXPECT_EQ(detector.update(true, 40.0F, 0.81F), PinchEvent::kStart);  // strength alone starts
  EXPECT_EQ(detector.update(true, 40.0F, 0.6F), PinchEvent::kNone);    // strength not below 0.5
  EXPECT_EQ(detector.update(true, 25.0F, 0.1F), PinchEvent::kNone);    // distance not above 30
  EXPECT_EQ(detector.update(true, 31.0F, 0.49F), PinchEvent::kEnd);
  EXPECT_EQ(detector.update(true, 31.0F, 0.79F), PinchEvent::kNone);
}

TEST(PinchDetector, LosingTheHandEndsAPinchAndNoHandNeverStartsOne) {
  PinchDetector detector;
  EXPECT_EQ(detector.update(false, 5.0F, 1.0F), PinchEvent::kNone);
  EXPECT_EQ(detector.update(true, 5.0F, 1.0F), PinchEvent::kStart);
  EXPECT_EQ(detector.update(false, 5.0F, 1.0F), PinchEvent::kEnd);
  EXPECT_EQ(detector.update(true, std::numeric_limits<float>::quiet_NaN(), 1.0F), PinchEvent::kNone);
  EXPECT_EQ(detector.update(true, 5.0F, 1.0F), PinchEvent::kStart);
  EXPECT_EQ(detector.update(true, std::numeric_limits<float>::infinity(), 0.0F), PinchEvent::kEnd);
}
