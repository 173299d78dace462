#include "handtrack/synth/two_hand_motions.hpp"

#include "angles.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace handtrack::synth {
namespace {

using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using HandAngles = std::array<FingerAngles, kNumFingers>;

enum Scene { kApart, kClap, kCross, kPinch, kReach };  // kTwoHandMotionNames order

struct SceneRecipe {
  std::string_view description;
  std::array<std::string_view, kTwoHands> finger_motions;  // motions.hpp names; "" = flat hands
  View view = View::kPalm;                                 // the camera arrangement
};

// clang-format off
constexpr std::array<SceneRecipe, kTwoHandMotionNames.size()> kRecipes = {{
    {"both palms toward the camera ~200 mm apart, the right hand fingerwave, the left flexex1",
     {"fingerwave", "flexex1"}},
    {"palms facing each other approach, touch and part (a 2 s cycle)", {"", ""}},
    {"the right hand passes in front of the left: they cross in the image and swap sides (a 4 s cycle)",
     {"adbadd", "fingerwave"}},
    {"both hands pinch, the left 0.8 s behind, palms turned 20 deg toward each other", {"pinch", "pinch"}},
    {"a head-mounted camera over both hands reaching forward: backs toward it, the right hand on the right",
     {"pinch", "fingerwave"}, View::kHeadMounted},
}};
// clang-format on

// Where a hand held up in front of the camera is (design poses, two_hand_motions.hpp: a right hand
// on the image's left), before its drift.
constexpr double kApartHalfSeparationMm = 100.0;  // two_apart: palm centres 200 mm apart at rest
constexpr double kPinchHalfSeparationMm = 105.0;
constexpr double kPinchTurnRad = -20.0 * std::numbers::pi / 180.0;  // about y: the palm toward the other hand
constexpr double kPinchLagSeconds = 0.8;                             // a third of pinch's 2.4 s cycle
constexpr double kHeldHeightMm = 15.0;                               // palm centre y (down)
constexpr double kHeldDepthMm = 420.0;
// two_reach: the palm centres 200 mm apart at the head-mounted arrangement's 330 mm (views.cpp),
// where the design pose is placed along its ray; the right hand on the image's right (x > 0).
constexpr double kReachHalfSeparationMm = 100.0;
constexpr double kReachDepthMm = 330.0;

// two_cross: x = -kCrossHalfWidthMm cos(2 pi tau / kCrossCycleSeconds) for both design poses (so
// the right hand goes from the left of the image to the right and back, the left hand the other
// way), the right hand nearer.
constexpr double kCrossCycleSeconds = 4.0;
constexpr double kCrossHalfWidthMm = 115.0;
constexpr std::array<double, kTwoHands> kCrossDepthMm = {360.0, 490.0};   // 130 mm between the palms
constexpr std::array<double, kTwoHands> kCrossHeightMm = {25.0, -15.0};   // overlapping in the image

// two_clap: design palm centre (-s/2, kHeldHeightMm, kHeldDepthMm), turned by Ry(-75 deg): the palm
// normal (-z at r = 0) goes to (sin 75, 0, -cos 75), toward +x (the other hand) and a little toward
// the camera, the thumb away from it. Mirrored, the left hand turns the other way: the palms face.
constexpr double kClapCycleSeconds = 2.0;
constexpr double kClapApartMm = 200.0;  // palm centres' separation when apart
constexpr double kClapTurnRad = -75.0 * std::numbers::pi / 180.0;
// Flat hands for clapping: fingers straight and together, the thumb alongside the index finger in
// the palm's plane (mean adult: its tip 0.3 mm palmar of the palm's mid-plane, where the thumb of
// {0.3, 0, 0.05, 0.05} stands 34 mm out of it and meets the other thumb long before the palms meet).
const HandAngles kFlatFingers = {{{0.55, -0.25, 0.0, 0.1},
                                  {0.05, 0.0, 0.05, 0.0},
                                  {0.0, 0.0, 0.05, 0.0},
                                  {-0.05, 0.0, 0.05, 0.0},
                                  {-0.1, 0.0, 0.05, 0.0}}};

// R = Rz(z) Ry(y) Rx(x), angles in radians about the camera's axes.
Matrix3d turn_zyx(const Vector3d& rad) {
  return (AngleAxisd(rad.z(), Vector3d::UnitZ()) * AngleAxisd(rad.y(), Vector3d::UnitY()) *
          AngleAxisd(rad.x(), Vector3d::UnitX()))
      .toRotationMatrix();
}

// A held hand's slow independent drift (phase `phi` per hand, incommensurate frequencies as
// motions.cpp's sway): +-12 mm across, +-15 mm up and down, +-35 mm in depth, turns of 0.10-0.15 rad.
struct Drift {
  Vector3d offset_mm;
  Matrix3d turn;
};
Drift drift(double tau, double phi) {
  const auto s = [&](double hz, double phase) { return std::sin(kTwoPi * hz * tau + phase + phi); };
  return {Vector3d(12.0 * s(0.11, 0.0), 15.0 * s(0.07, 1.0), 35.0 * s(0.09, 2.0)),
          turn_zyx(Vector3d(0.12 * s(0.10, 0.5), 0.15 * s(0.08, 1.5), 0.10 * s(0.12, 2.5)))};
}
constexpr std::array<double, kTwoHands> kDriftPhase = {0.0, 1.7};

// Palms apart 1 -> touching 0 over a clap cycle: closing over the first 40 %, touching for 15 %,
// opening over the rest; cosine easing (no velocity at either end of a stroke).
double clap_openness(double tau) {
  double phase = tau / kClapCycleSeconds;
  phase -= std::floor(phase);
  if (phase < 0.4) return 0.5 + 0.5 * std::cos(std::numbers::pi * phase / 0.4);
  if (phase < 0.55) return 0.0;
  return 0.5 - 0.5 * std::cos(std::numbers::pi * (phase - 0.55) / 0.45);
}

// The clap's design pose at palm-centre separation `separation_mm`, shifted and pitched by the
// pair's common drift. Both hands drift alike: the same translation and the same pitch (about the
// camera x axis, the line through both palm centres) move the pair rigidly, and M Rx M = Rx for the
// mirror M = diag(-1, 1, 1), so where the palms touch does not depend on the drift.
HandPose clap_pose(const HandShape& shape, double separation_mm, double pitch_rad, const Vector3d& offset_mm) {
  HandPose pose;
  pose.fingers = kFlatFingers;
  const Matrix3d turn =
      (AngleAxisd(pitch_rad, Vector3d::UnitX()) * AngleAxisd(kClapTurnRad, Vector3d::UnitY())).toRotationMatrix();
  place_palm(pose, shape, turn, Vector3d(-0.5 * separation_mm, kHeldHeightMm, kHeldDepthMm) + offset_mm);
  return pose;
}

// The solids of both hands as the camera sees them (hand 1 mirrored).
double hands_gap_mm(const std::array<HandShape, kTwoHands>& shapes, const TwoHandPoses& poses) {
  std::array<std::vector<ConeSphere>, kTwoHands> solids;
  for (size_t k = 0; k < kTwoHands; ++k) {
    posed_primitives(shapes[k], poses[k], camera_frame_joints(shapes[k], poses[k]), solids[k]);
  }
  mirror_x(solids[1]);
  return surface_gap_mm(solids[0], solids[1]);
}

// The separation at which the flat palms touch: the gap is negative at 0 (the hands inside each
// other) and positive at kClapApartMm; bisection to 0.01 mm, keeping the side where they do not
// overlap.
double solve_clap_contact(const std::array<HandShape, kTwoHands>& shapes) {
  const auto gap = [&](double s) {
    return hands_gap_mm(shapes, {clap_pose(shapes[0], s, 0.0, Vector3d::Zero()),
                                 clap_pose(shapes[1], s, 0.0, Vector3d::Zero())});
  };
  double lo = 0.0, hi = kClapApartMm;
  if (!(gap(hi) > 0.0)) throw std::logic_error("two_clap: the hands overlap even when apart");
  while (hi - lo > 0.01) {
    const double mid = 0.5 * (lo + hi);
    (gap(mid) > 0.0 ? hi : lo) = mid;
  }
  return hi;
}

}  // namespace

bool is_two_hand_motion(std::string_view name) {
  return std::find(kTwoHandMotionNames.begin(), kTwoHandMotionNames.end(), name) != kTwoHandMotionNames.end();
}

std::string_view two_hand_motion_description(std::string_view name) {
  for (size_t i = 0; i < kTwoHandMotionNames.size(); ++i) {
    if (kTwoHandMotionNames[i] == name) return kRecipes[i].description;
  }
  return {};
}

View two_hand_view(std::string_view name) {
  for (size_t i = 0; i < kTwoHandMotionNames.size(); ++i) {
    if (kTwoHandMotionNames[i] == name) return kRecipes[i].view;
  }
  return View::kPalm;
}

View seen_in(std::string_view motion, View view) { return is_two_hand_motion(motion) ? two_hand_view(motion) : view; }

TwoHandMotion::TwoHandMotion(std::string_view name, int frames, double fps,
                             const std::array<HandShape, kTwoHands>& shapes)
    : frames_(frames), fps_(fps), shapes_(shapes) {
  const auto it = std::find(kTwoHandMotionNames.begin(), kTwoHandMotionNames.end(), name);
  if (it == kTwoHandMotionNames.end()) {
    std::string all;
    for (auto n : kTwoHandMotionNames) all += (all.empty() ? "" : ", ") + std::string(n);
    throw std::invalid_argument("unknown two-hand motion '" + std::string(name) + "' (expected one of: " + all + ")");
  }
  if (frames < 1) throw std::invalid_argument("frames must be >= 1, got " + std::to_string(frames));
  if (!(fps > 0.0 && std::isfinite(fps))) throw std::invalid_argument("fps must be > 0");
  index_ = static_cast<int>(it - kTwoHandMotionNames.begin());
  for (size_t k = 0; k < kTwoHands; ++k) {
    const std::string_view fingers = kRecipes[static_cast<size_t>(index_)].finger_motions[k];
    if (!fingers.empty()) fingers_[k].emplace(fingers, frames, fps, shapes_[k]);
  }
  if (index_ == kClap) clap_contact_mm_ = solve_clap_contact(shapes_);
}

TwoHandPoses TwoHandMotion::pose(int frame) const {
  const double tau = motion_time(frame);
  TwoHandPoses poses;
  if (index_ == kClap) {
    // The pair's common drift: depth and height, and a pitch.
    const Vector3d offset(0.0, 10.0 * std::sin(kTwoPi * 0.07 * tau), 25.0 * std::sin(kTwoPi * 0.09 * tau + 1.0));
    const double pitch = 0.12 * std::sin(kTwoPi * 0.10 * tau + 0.5);
    const double separation = clap_contact_mm_ + (kClapApartMm - clap_contact_mm_) * clap_openness(tau);
    for (size_t k = 0; k < kTwoHands; ++k) poses[k] = clap_pose(shapes_[k], separation, pitch, offset);
    return poses;
  }
  for (size_t k = 0; k < kTwoHands; ++k) {
    const double lag = index_ == kPinch ? static_cast<double>(k) * kPinchLagSeconds : 0.0;
    HandPose& pose = poses[k];
    pose.fingers = fingers_[k]->pose_at(tau - lag).fingers;
    const Drift d = drift(tau, kDriftPhase[k]);
    switch (index_) {
      case kApart:
        place_palm(pose, shapes_[k], d.turn, Vector3d(-kApartHalfSeparationMm, kHeldHeightMm, kHeldDepthMm) + d.offset_mm);
        break;
      case kPinch:
        place_palm(pose, shapes_[k], d.turn * AngleAxisd(kPinchTurnRad, Vector3d::UnitY()).toRotationMatrix(),
                   Vector3d(-kPinchHalfSeparationMm, kHeldHeightMm, kHeldDepthMm) + d.offset_mm);
        break;
      case kReach:
        // Held as in front of a desk camera, then turned and placed as the head-mounted arrangement
        // holds one hand (views.hpp): about its own palm centre, along the ray to 330 mm.
        place_palm(pose, shapes_[k], d.turn,
                   Vector3d(kReachHalfSeparationMm, kHeldHeightMm, kReachDepthMm) + d.offset_mm);
        pose = view_pose(View::kHeadMounted, pose, shapes_[k]);
        break;
      default: {  // kCross: a third of the drift's offset, so the two depths stay apart
        const double x = -kCrossHalfWidthMm * std::cos(kTwoPi * tau / kCrossCycleSeconds);
        place_palm(pose, shapes_[k], d.turn, Vector3d(x, kCrossHeightMm[k], kCrossDepthMm[k]) + d.offset_mm / 3.0);
        break;
      }
    }
  }
  return poses;
}

}  // namespace handtrack::synth
