#include "handtrack/synth/views.hpp"

#include <Eigen/Geometry>

#include <numbers>

namespace handtrack::synth {
namespace {

using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;

double deg(double d) { return d * std::numbers::pi / 180.0; }

struct Arrangement {
  View view;
  std::string_view name;
  std::string_view description;
  double turn_deg;   // about the hand's finger axis: 0 palm, 180 back, 90 thumb side toward the camera
  double tip_deg;    // about the camera x axis: + fingers toward the camera, - away
  double palm_depth_mm;  // 0: where the motion puts it
  double near_body_behind_mm;  // Background::kNearBody this much farther than in the palm view
};

// clang-format off
constexpr std::array<Arrangement, kViews.size()> kArrangements = {{
    {View::kPalm, "palm", "desk camera facing the user, the palm toward it (the Dexter motions)", 0, 0, 0, 0},
    {View::kBack, "back", "desk camera, the back of the hand toward it (pointing at the screen)", 180, 0, 0, 90},
    {View::kSide, "side", "desk camera, the thumb side toward it", 90, 0, 0, 90},
    {View::kFingersToward, "fingers-toward", "the fingers tipped 50 deg toward the camera", 0, 50, 0, 0},
    {View::kFingersAway, "fingers-away", "the fingers tipped 50 deg away from the camera", 0, -50, 0, 90},
    {View::kHeadMounted, "head-mounted",
     "egocentric camera behind the hand: back toward it, fingers 65 deg away, forearm from the image bottom",
     180, -65, 330, 0},
}};
// clang-format on

const Arrangement& arrangement(View view) { return kArrangements[static_cast<size_t>(view)]; }

}  // namespace

std::string_view view_name(View view) { return arrangement(view).name; }

std::string_view view_description(View view) { return arrangement(view).description; }

double near_body_behind_mm(View view) { return arrangement(view).near_body_behind_mm; }

std::optional<View> parse_view(std::string_view name) {
  for (const auto& a : kArrangements) {
    if (a.name == name) return a.view;
  }
  return std::nullopt;
}

HandPose view_pose(View view, const HandPose& pose, const HandShape& shape) {
  const Arrangement& a = arrangement(view);
  if (view == View::kPalm) return pose;
  // camera_R_hand = exp(r) R0 (hand_model.hpp); the palm centre p = t + R palm_centre stays put
  // (or moves to the arrangement's depth) while R turns.
  const Matrix3d r = camera_R_hand(pose.rotation);
  const Vector3d palm = pose.translation_mm + r * shape.palm_centre_mm;
  const Matrix3d turned = r * AngleAxisd(deg(a.tip_deg), Vector3d::UnitX()).toRotationMatrix() *
                          AngleAxisd(deg(a.turn_deg), Vector3d::UnitY()).toRotationMatrix();
  const Matrix3d r0 = camera_R_hand(Vector3d::Zero());
  const AngleAxisd exp_r(turned * r0.transpose());
  HandPose out = pose;
  out.rotation = exp_r.angle() * exp_r.axis();
  Vector3d placed = palm;
  if (a.palm_depth_mm > 0.0) placed *= a.palm_depth_mm / palm.z();  // along the same ray
  out.translation_mm = placed - turned * shape.palm_centre_mm;
  return out;
}

HandShape view_shape(View view, HandShape shape) {
  // Head-mounted: from the wrist down toward the image bottom and 53 deg from the image plane
  // toward the camera (12 deg from the straight wrist at the arrangement's rest pose).
  if (view == View::kHeadMounted) shape.forearm_camera_direction = Vector3d(0.0, 0.6, -0.8);
  return shape;
}

HandShape with_upper_arm(View view, HandShape shape) {
  if (view == View::kHeadMounted) return shape;
  shape.upper_arm_camera_direction = Vector3d(-0.3, -0.5, 0.8).normalized();
  shape.upper_arm_mm = 300.0 * shape.subject.length;
  return shape;
}

HandShape without_arm(HandShape shape) {
  shape.forearm_shown = false;
  return shape;
}

}  // namespace handtrack::synth
