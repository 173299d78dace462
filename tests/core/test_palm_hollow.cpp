// How the depth curves across a fit's palm (palm_hollow.hpp): the sign that tells a palm facing
// the camera from a back, on surfaces of known shape.
#include "handtrack/core/palm_hollow.hpp"

#include "handtrack/core/hand_layout.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace handtrack {
namespace {

constexpr double kSurfaceMm = 400.0;    // the hand's surface at its middle
constexpr double kBonesMm = 410.0;      // the fit's joints, 10 mm inside the hand
constexpr double kHalfWidthMm = 27.0;   // the index and little knuckles from the middle
constexpr double kHalfLengthMm = 45.0;  // wrist and middle knuckle from the palm centre

// A fit of a hand facing the camera square on, fingers up, its palm centre on the optical axis;
// `palm_toward_camera` false: its back.
TrackerOutput facing_fit(bool palm_toward_camera) {
  TrackerOutput fit;
  fit.state = TrackingState::kTracking;
  fit.joints[kWristJoint] = {0.0, kHalfLengthMm, kBonesMm};
  fit.joints[joint_index(kIndex, 0)] = {kHalfWidthMm, -kHalfLengthMm, kBonesMm};
  fit.joints[joint_index(kMiddle, 0)] = {0.0, -kHalfLengthMm, kBonesMm};
  fit.joints[joint_index(kRing, 0)] = {-kHalfWidthMm / 3.0, -kHalfLengthMm, kBonesMm};
  fit.joints[joint_index(kLittle, 0)] = {-kHalfWidthMm, -kHalfLengthMm, kBonesMm};
  fit.palm_centre = {0.0, 0.0, kBonesMm};
  fit.palm_normal = {0.0, 0.0, palm_toward_camera ? -1.0 : 1.0};
  return fit;
}

// A hand's surface seen by the SPEC camera: depth kSurfaceMm - sides_mm (x / kHalfWidthMm)^2 over
// the hand (|x| <= 40 mm, |y| <= 60 mm), so its sides at the knuckles stand sides_mm toward the
// camera from its middle; and where `folded`, fingers folded over the palm's middle, 30 mm nearer.
DepthInput hand_surface(double sides_mm, bool folded = false) {
  DepthInput input;
  const CameraIntrinsics& cam = input.camera;
  const size_t pixels = static_cast<size_t>(cam.width) * static_cast<size_t>(cam.height);
  input.filtered_mm.assign(pixels, 0.0F);
  input.hand_mask.assign(pixels, 0);
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d ray = cam.unproject(u, v, kSurfaceMm);
      if (std::abs(ray.x()) > 40.0 || std::abs(ray.y()) > 60.0) continue;
      const double t = ray.x() / kHalfWidthMm;
      double depth = kSurfaceMm - sides_mm * t * t;
      if (folded && std::abs(ray.x()) < 20.0 && std::abs(ray.y()) < 30.0) depth -= 30.0;
      const size_t i = static_cast<size_t>(v) * static_cast<size_t>(cam.width) + static_cast<size_t>(u);
      input.filtered_mm[i] = static_cast<float>(depth);
      input.hand_mask[i] = 1;
    }
  }
  return input;
}

TEST(PalmHollow, AHollowReadsPositiveAConvexBackNegativeAFlatHandNearZero) {
  for (const bool palm : {true, false}) {  // the fit's own side does not enter: the depth's shape does
    const TrackerOutput fit = facing_fit(palm);
    const std::optional<double> hollow = palm_hollow_mm(hand_surface(6.0), fit);
    const std::optional<double> convex = palm_hollow_mm(hand_surface(-6.0), fit);
    const std::optional<double> flat = palm_hollow_mm(hand_surface(0.0), fit);
    ASSERT_TRUE(hollow && convex && flat);
    EXPECT_NEAR(*hollow, 6.0, 0.5);
    EXPECT_NEAR(*convex, -6.0, 0.5);
    EXPECT_NEAR(*flat, 0.0, 0.3);
  }
}

TEST(PalmHollow, APalmItCannotSeeTellsNothing) {
  const TrackerOutput fit = facing_fit(true);
  EXPECT_FALSE(palm_hollow_mm(hand_surface(6.0, /*folded=*/true), fit)) << "fingers folded over the palm";
  DepthInput nothing = hand_surface(6.0);
  nothing.hand_mask.assign(nothing.hand_mask.size(), 0);
  EXPECT_FALSE(palm_hollow_mm(nothing, fit)) << "no hand pixels";
  TrackerOutput broken = fit;
  broken.joints[kWristJoint].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(palm_hollow_mm(hand_surface(6.0), broken)) << "a fit that is not finite";
  TrackerOutput edge_on = fit;
  edge_on.palm_normal = {1.0, 0.0, 0.0};  // the knuckles' line along the palm normal: no width across
  EXPECT_FALSE(palm_hollow_mm(hand_surface(6.0), edge_on)) << "a fit seen edge-on";
}

}  // namespace
}  // namespace handtrack
