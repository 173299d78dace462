// A camera mounted turned (camera_roll.hpp): the image turned upright is the same scene, and a pose
// tracked in it turns back into the camera's frame with its parameters.
#include "handtrack/core/camera_roll.hpp"
#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/kinematics.hpp"

#include <gtest/gtest.h>

#include <random>

namespace handtrack {
namespace {

constexpr CameraRoll kRolls[] = {CameraRoll::k0, CameraRoll::k90, CameraRoll::k180, CameraRoll::k270};

// An off-centre principal point and unequal focal lengths, so that a swap or a missing flip shows.
CameraIntrinsics odd_camera() {
  CameraIntrinsics c;
  c.width = 37;
  c.height = 23;
  c.fx = 41.0;
  c.fy = 29.0;
  c.cx = 15.25;
  c.cy = 12.75;
  return c;
}

TEST(CameraRoll, EveryUprightPixelShowsThePointTheCameraSawThere) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> depth(300.0F, 700.0F);
  DepthImage image;
  image.camera = odd_camera();
  image.depth_mm.resize(static_cast<size_t>(image.camera.width * image.camera.height));
  for (auto& d : image.depth_mm) d = depth(rng);
  for (const CameraRoll roll : kRolls) {
    DepthImage upright;
    turn_upright(image, roll, &upright);
    ASSERT_EQ(upright.depth_mm.size(), image.depth_mm.size());
    ASSERT_EQ(upright.camera.problem(), "");
    for (int v = 0; v < upright.height(); ++v) {
      for (int u = 0; u < upright.width(); ++u) {
        // The point behind the upright pixel, in the camera's frame, lands on the camera's pixel of
        // the same depth.
        const Eigen::Vector3d p = turn_to_camera(roll, upright.camera.unproject(u, v, upright.at(u, v)));
        const Eigen::Vector2d pixel = image.camera.project(p);
        const int cu = static_cast<int>(std::lround(pixel.x()));
        const int cv = static_cast<int>(std::lround(pixel.y()));
        ASSERT_NEAR(pixel.x(), cu, 1e-9) << degrees(roll);
        ASSERT_NEAR(pixel.y(), cv, 1e-9) << degrees(roll);
        ASSERT_TRUE(cu >= 0 && cu < image.width() && cv >= 0 && cv < image.height()) << degrees(roll);
        ASSERT_EQ(image.at(cu, cv), upright.at(u, v)) << degrees(roll) << " at " << u << "," << v;
      }
    }
  }
}

TEST(CameraRoll, NamesTheQuarterTurnsAndNothingElse) {
  EXPECT_EQ(parse_camera_roll("0"), CameraRoll::k0);
  EXPECT_EQ(parse_camera_roll("90"), CameraRoll::k90);
  EXPECT_EQ(parse_camera_roll("180"), CameraRoll::k180);
  EXPECT_EQ(parse_camera_roll("-180"), CameraRoll::k180);
  EXPECT_EQ(parse_camera_roll("270"), CameraRoll::k270);
  EXPECT_EQ(parse_camera_roll("-90"), CameraRoll::k270);
  for (const char* bad : {"45", "360", "", "90 ", "ninety", "1e2", "+90"}) {
    EXPECT_FALSE(parse_camera_roll(bad).has_value()) << bad;
  }
}

// A pose turned back: its joints are the upright joints turned, and its parameters pose the model at
// those joints (a left hand's through the mirror, as Tracker reports it).
TEST(CameraRoll, APoseTurnsBackWithItsParameters) {
  const HandModel model = HandModel::default_adult();
  PoseParams params = PoseParams::Zero();
  params.segment<3>(kTranslationParam) = Eigen::Vector3d(30.0, -20.0, 420.0);
  params.segment<3>(kRotationParam) = Eigen::Vector3d(0.4, -0.3, 0.9);
  params[angle_param(kIndex, 1)] = 0.5;
  params[angle_param(kThumb, 0)] = 0.3;
  for (const Handedness hand : {Handedness::kRight, Handedness::kLeft}) {
    const double mirror = hand == Handedness::kLeft ? -1.0 : 1.0;
    TrackerOutput upright;
    upright.handedness = hand;
    upright.params = params;
    const PosedHand posed(model, params);
    for (int j = 0; j < kNumJoints; ++j) {
      upright.joints[static_cast<size_t>(j)] = posed.joints()[static_cast<size_t>(j)];
      upright.joints[static_cast<size_t>(j)].x() *= mirror;
    }
    upright.palm_normal = Eigen::Vector3d(0.0, 0.6, 0.8);
    for (const CameraRoll roll : kRolls) {
      TrackerOutput out = upright;
      turn_to_camera(roll, &out);
      const PosedHand turned(model, out.params);
      for (int j = 0; j < kNumJoints; ++j) {
        const Eigen::Vector3d want = turn_to_camera(roll, upright.joints[static_cast<size_t>(j)]);
        EXPECT_LT((out.joints[static_cast<size_t>(j)] - want).norm(), 1e-12);
        Eigen::Vector3d from_params = turned.joints()[static_cast<size_t>(j)];
        from_params.x() *= mirror;
        EXPECT_LT((from_params - want).norm(), 1e-9) << to_string(hand) << " " << degrees(roll) << " joint " << j;
      }
      EXPECT_LT((out.palm_normal - turn_to_camera(roll, upright.palm_normal)).norm(), 1e-12);
    }
  }
}

}  // namespace
}  // namespace handtrack
